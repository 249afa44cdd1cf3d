#include "proto/dds_entities.h"

#include <map>
#include <mutex>
#include <utility>

#include "proto/dds_log.h"

namespace sage::proto {

namespace {

std::string FormatDdsError(std::string_view operation, dds_return_t retcode) {
  std::string message(operation);
  message += ": ";
  message += dds_strretcode(retcode);
  return message;
}

// One explicitly created domain, shared by every Participant of this process on that domain.
// Cyclone keeps an explicitly created domain until it is deleted, and dds_create_domain fails
// with PRECONDITION_NOT_MET for a domain that exists, hence a per-process registry.
struct DomainRegistry {
  std::mutex mutex;
  struct Slot {
    std::weak_ptr<Entity> domain;
    std::string config_xml;
  };
  std::map<uint32_t, Slot> slots;
};

DomainRegistry& Registry() {
  static DomainRegistry registry;
  return registry;
}

std::shared_ptr<Entity> AcquireDomain(uint32_t domain_id, const std::string& config_xml) {
  RouteDdsLog();  // before Cyclone's first word: its warnings in the mission's words, not raw on a terminal
  DomainRegistry& registry = Registry();
  std::lock_guard lock(registry.mutex);
  DomainRegistry::Slot& slot = registry.slots[domain_id];
  if (std::shared_ptr<Entity> existing = slot.domain.lock()) {
    if (slot.config_xml != config_xml) {
      throw std::invalid_argument("domain " + std::to_string(domain_id) +
                                  " already exists in this process with a different config");
    }
    return existing;
  }
  const std::string operation = "dds_create_domain(" + std::to_string(domain_id) + ")";
  const ParticipantStartup starting;  // the domain's network starts here: peers may be heard already
  Entity created(CheckDds(dds_create_domain(domain_id, config_xml.c_str()), operation));
  // The deleter takes the registry lock so that a Participant created on this domain id while
  // the last one is being destroyed waits for the deletion instead of failing.
  std::shared_ptr<Entity> domain(new Entity(std::move(created)), [](Entity* entity) {
    std::lock_guard deleting(Registry().mutex);
    delete entity;
  });
  slot.domain = domain;
  slot.config_xml = config_xml;
  return domain;
}

}  // namespace

DdsError::DdsError(std::string_view operation, dds_return_t retcode)
    : std::runtime_error(FormatDdsError(operation, retcode)), retcode_(retcode) {}

dds_return_t CheckDds(dds_return_t rc, std::string_view operation) {
  if (rc < 0) throw DdsError(operation, rc);
  return rc;
}

Entity& Entity::operator=(Entity&& other) noexcept {
  if (this != &other) {
    Reset();
    handle_ = other.Release();
  }
  return *this;
}

dds_entity_t Entity::Release() noexcept { return std::exchange(handle_, 0); }

void Entity::Reset() noexcept {
  if (handle_ > 0) {
    // ALREADY_DELETED / BAD_PARAMETER here only mean a parent was deleted first.
    (void)dds_delete(handle_);
  }
  handle_ = 0;
}

Participant::Participant(uint32_t domain_id, const std::string& config_xml)
    : domain_id_(domain_id), domain_(AcquireDomain(domain_id, config_xml)) {
  const std::string operation = "dds_create_participant(" + std::to_string(domain_id) + ")";
  const ParticipantStartup starting;  // a peer heard before this participant is set up may be refused for a moment
  participant_ = Entity(CheckDds(dds_create_participant(domain_id, nullptr, nullptr), operation));
}

namespace detail {

Entity CreateTopic(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                   const std::string& name) {
  return Entity(CheckDds(dds_create_topic(participant, descriptor, name.c_str(), nullptr, nullptr),
                         "dds_create_topic(" + name + ")"));
}

}  // namespace detail

}  // namespace sage::proto
