#pragma once
// RAII owners of Cyclone DDS entities. Only proto/ and the one transport file per side include
// this header: algorithms never see dds/dds.h. Typed endpoints (Writer<T>, Reader<T>) live in
// proto/dds_endpoints.h; message types and their topics in proto/messages.h.
#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

namespace sage::proto {

/// A DDS call returned a negative retcode. what() is "<operation>: <dds_strretcode(retcode)>",
/// e.g. "dds_create_writer(rt/sage/ergodic_target): Inconsistent Policy".
class DdsError : public std::runtime_error {
 public:
  DdsError(std::string_view operation, dds_return_t retcode);
  /// The negative DDS_RETCODE_* value.
  dds_return_t retcode() const noexcept { return retcode_; }

 private:
  dds_return_t retcode_;
};

/// Returns `rc` unchanged when it is >= 0 (a handle or a count); throws DdsError naming
/// `operation` otherwise.
dds_return_t CheckDds(dds_return_t rc, std::string_view operation);

/// Owns one dds_entity_t and dds_delete()s it on destruction (which also deletes its children).
/// Move-only. A handle of 0 means "owns nothing".
class Entity {
 public:
  Entity() noexcept = default;
  /// Takes ownership of `handle` (must be > 0, e.g. the checked result of a dds_create_*).
  explicit Entity(dds_entity_t handle) noexcept : handle_(handle) {}
  ~Entity() { Reset(); }
  Entity(Entity&& other) noexcept : handle_(other.Release()) {}
  Entity& operator=(Entity&& other) noexcept;
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;

  /// The owned handle (0 if none); still owned by this object.
  dds_entity_t get() const noexcept { return handle_; }
  /// Gives up ownership without deleting; returns the handle.
  dds_entity_t Release() noexcept;
  /// Deletes the owned entity now, if any. Errors are ignored: a parent deleted first (e.g. the
  /// participant before its writers) already deleted this entity.
  void Reset() noexcept;

 private:
  dds_entity_t handle_ = 0;
};

/// A domain participant on domain `domain_id` configured by `config_xml` (see
/// proto/dds_config.h), without any environment variable: the first Participant of a domain in
/// this process creates the domain with dds_create_domain(domain_id, config_xml); later ones on
/// the same domain share it (their config must be identical). The domain is deleted with its
/// last Participant. Endpoints created from a Participant must be destroyed before it (deleting
/// the participant deletes them; their own destructors then do nothing harmful). Move-only.
/// Never fork() while any Participant exists: Cyclone's threads do not survive a fork.
class Participant {
 public:
  /// domain_id in 0..232 (Cyclone's default port mapping); throws DdsError on failure, e.g.
  /// "dds_create_domain(7): Error" when no participant index is free (see LocalhostConfigXml).
  Participant(uint32_t domain_id, const std::string& config_xml);
  Participant(Participant&&) noexcept = default;
  Participant& operator=(Participant&&) noexcept = default;

  /// The participant handle, owned by this object.
  dds_entity_t handle() const noexcept { return participant_.get(); }
  /// The DDS domain id this participant lives in.
  uint32_t domain_id() const noexcept { return domain_id_; }

 private:
  uint32_t domain_id_;
  std::shared_ptr<Entity> domain_;  // shared with other Participants of the same domain
  Entity participant_;              // declared after domain_: deleted before it
};

/// Descriptor and default topic name of message type T; specialised in proto/messages.h.
template <class T>
struct MessageTraits;

namespace detail {
/// dds_create_topic(participant, descriptor, name) as an owned Entity; throws DdsError.
Entity CreateTopic(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                   const std::string& name);
}  // namespace detail

/// A topic entity of type T (a generated IDL struct) named by MessageTraits<T> unless `name` is
/// given, for raw DDS calls. Writer<T> and Reader<T> create their own topic entity instead of
/// taking a Topic: Cyclone refuses to delete a topic that still has endpoints, so a shared one
/// would make destruction order matter. Move-only.
template <class T>
class Topic {
 public:
  /// Creates the topic in `participant` (a Participant or raw participant handle).
  explicit Topic(dds_entity_t participant, std::string name = MessageTraits<T>::kTopicName)
      : name_(std::move(name)),
        entity_(detail::CreateTopic(participant, MessageTraits<T>::Descriptor(), name_)) {}
  explicit Topic(const Participant& participant, std::string name = MessageTraits<T>::kTopicName)
      : Topic(participant.handle(), std::move(name)) {}

  /// The topic handle, owned by this object.
  dds_entity_t handle() const noexcept { return entity_.get(); }
  /// The DDS topic name, e.g. "rt/sage/vehicle_state".
  const std::string& name() const noexcept { return name_; }

 private:
  std::string name_;
  Entity entity_;
};

}  // namespace sage::proto
