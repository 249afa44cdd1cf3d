#include "proto/dds_endpoints.h"

#include <cstring>
#include <limits>
#include <new>

namespace sage::proto {

namespace {

// A zeroed sample is what Cyclone expects in caller-owned buffers: null strings and empty
// sequences (_buffer null, _maximum 0) are allocated by the deserialiser as needed.
void* AllocateZeroedSample(const dds_topic_descriptor_t* descriptor) {
  void* sample = dds_alloc(descriptor->m_size);
  if (sample == nullptr) throw std::bad_alloc();
  std::memset(sample, 0, descriptor->m_size);
  return sample;
}

uint32_t CheckedCount(std::size_t max_samples) {
  if (max_samples == 0 || max_samples > std::numeric_limits<int32_t>::max()) {
    throw std::invalid_argument("max_samples = " + std::to_string(max_samples) +
                                ": must be in 1..2^31-1");
  }
  return static_cast<uint32_t>(max_samples);
}

}  // namespace

OwnedSample::~OwnedSample() {
  // DDS_FREE_ALL frees the strings and sequence buffers the deserialiser allocated, then the
  // sample itself (allocated with dds_alloc).
  if (sample_ != nullptr) dds_sample_free(sample_, descriptor_, DDS_FREE_ALL);
}

OwnedSample& OwnedSample::operator=(OwnedSample&& other) noexcept {
  if (this != &other) {
    if (sample_ != nullptr) dds_sample_free(sample_, descriptor_, DDS_FREE_ALL);
    sample_ = std::exchange(other.sample_, nullptr);
    descriptor_ = other.descriptor_;
  }
  return *this;
}

namespace detail {

WriterCore::WriterCore(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                       const std::string& topic_name, const Qos& qos)
    : topic_name_(topic_name), topic_(CreateTopic(participant, descriptor, topic_name)) {
  writer_ = Entity(CheckDds(dds_create_writer(participant, topic_.get(), qos.get(), nullptr),
                            "dds_create_writer(" + topic_name_ + ")"));
}

void WriterCore::Write(const void* sample) {
  CheckDds(dds_write(writer_.get(), sample), "dds_write(" + topic_name_ + ")");
}

void WriterCore::Dispose(const void* key_sample) {
  CheckDds(dds_dispose(writer_.get(), key_sample), "dds_dispose(" + topic_name_ + ")");
}

void WriterCore::Flush() { dds_write_flush(writer_.get()); }

void WriterCore::Unregister(const void* key_sample) {
  CheckDds(dds_unregister_instance(writer_.get(), key_sample),
           "dds_unregister_instance(" + topic_name_ + ")");
}

uint32_t WriterCore::MatchedReaders() const {
  dds_publication_matched_status_t status;
  CheckDds(dds_get_publication_matched_status(writer_.get(), &status),
           "dds_get_publication_matched_status(" + topic_name_ + ")");
  return status.current_count;
}

ReaderCore::ReaderCore(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                       const std::string& topic_name, const Qos& qos)
    : descriptor_(descriptor),
      topic_name_(topic_name),
      topic_(CreateTopic(participant, descriptor, topic_name)) {
  reader_ = Entity(CheckDds(dds_create_reader(participant, topic_.get(), qos.get(), nullptr),
                            "dds_create_reader(" + topic_name_ + ")"));
  // ANY state: invalid samples (instance disposed / no writers) must wake a waiter as well.
  read_condition_ = Entity(CheckDds(dds_create_readcondition(reader_.get(), DDS_ANY_STATE),
                                    "dds_create_readcondition(" + topic_name_ + ")"));
  waitset_ = Entity(CheckDds(dds_create_waitset(participant), "dds_create_waitset"));
  CheckDds(dds_waitset_attach(waitset_.get(), read_condition_.get(), 0),
           "dds_waitset_attach(" + topic_name_ + ")");
}

std::vector<std::pair<OwnedSample, dds_sample_info_t>> ReaderCore::TakeOwned(
    std::size_t max_samples) {
  const uint32_t count = CheckedCount(max_samples);
  while (free_buffers_.size() < count) {
    free_buffers_.emplace_back(AllocateZeroedSample(descriptor_), descriptor_);
  }
  std::vector<void*> buffers(count);
  for (uint32_t i = 0; i < count; ++i) buffers[i] = free_buffers_[i].mutable_get();
  std::vector<dds_sample_info_t> infos(count);
  // Non-null buffers: Cyclone deserialises into our memory instead of lending its own, so the
  // samples can outlive this call; OwnedSample frees them.
  const auto taken = static_cast<std::size_t>(
      CheckDds(dds_take(reader_.get(), buffers.data(), infos.data(), count, count),
               "dds_take(" + topic_name_ + ")"));
  std::vector<std::pair<OwnedSample, dds_sample_info_t>> samples;
  samples.reserve(taken);
  for (std::size_t i = 0; i < taken; ++i) {
    samples.emplace_back(std::move(free_buffers_[i]), infos[i]);
  }
  free_buffers_.erase(free_buffers_.begin(), free_buffers_.begin() + taken);
  return samples;
}

std::size_t ReaderCore::TakeLoaned(std::size_t max_samples, Visit visit, void* context) {
  const uint32_t count = CheckedCount(max_samples);
  std::vector<void*> buffers(count, nullptr);  // buffers[0] == null asks for a loan
  std::vector<dds_sample_info_t> infos(count);
  const dds_return_t taken =
      CheckDds(dds_take(reader_.get(), buffers.data(), infos.data(), count, count),
               "dds_take(" + topic_name_ + ")");
  if (taken == 0) return 0;  // Cyclone keeps no loan outstanding when nothing was taken
  try {
    for (dds_return_t i = 0; i < taken; ++i) visit(context, buffers[i], infos[i]);
  } catch (...) {
    (void)dds_return_loan(reader_.get(), buffers.data(), taken);
    throw;
  }
  CheckDds(dds_return_loan(reader_.get(), buffers.data(), taken),
           "dds_return_loan(" + topic_name_ + ")");
  return static_cast<std::size_t>(taken);
}

bool ReaderCore::WaitForData(std::chrono::nanoseconds timeout) {
  const dds_return_t triggered = CheckDds(
      dds_waitset_wait(waitset_.get(), nullptr, 0, static_cast<dds_duration_t>(timeout.count())),
      "dds_waitset_wait(" + topic_name_ + ")");
  return triggered > 0;
}

uint32_t ReaderCore::MatchedWriters() const {
  dds_subscription_matched_status_t status;
  CheckDds(dds_get_subscription_matched_status(reader_.get(), &status),
           "dds_get_subscription_matched_status(" + topic_name_ + ")");
  return status.current_count;
}

}  // namespace detail

}  // namespace sage::proto
