#pragma once
// Typed DDS writers and readers over the generated C structs of proto/sage_msgs.idl. The
// templates are thin: every DDS call is made (and checked) in dds_endpoints.cpp.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "proto/dds_entities.h"
#include "proto/qos.h"

namespace sage::proto {

/// One sample's memory owned outside Cyclone, released with dds_sample_free(DDS_FREE_ALL)
/// (which also frees its strings and sequences). Move-only.
class OwnedSample {
 public:
  OwnedSample(void* sample, const dds_topic_descriptor_t* descriptor) noexcept
      : sample_(sample), descriptor_(descriptor) {}
  ~OwnedSample();
  OwnedSample(OwnedSample&& other) noexcept
      : sample_(std::exchange(other.sample_, nullptr)), descriptor_(other.descriptor_) {}
  OwnedSample& operator=(OwnedSample&& other) noexcept;
  OwnedSample(const OwnedSample&) = delete;
  OwnedSample& operator=(const OwnedSample&) = delete;
  const void* get() const noexcept { return sample_; }
  /// The sample for Cyclone to fill (dds_take into caller-owned buffers); still owned here.
  void* mutable_get() noexcept { return sample_; }

 private:
  void* sample_;
  const dds_topic_descriptor_t* descriptor_;
};

/// A sample taken from a Reader<T> with its sample info. When info().valid_data is false the
/// sample only reports an instance state change and data() holds just the key fields (e.g.
/// vehicle_id) with everything else zero.
template <class T>
class Sample {
 public:
  Sample(OwnedSample data, const dds_sample_info_t& info) : data_(std::move(data)), info_(info) {}
  /// The message; strings and sequences live as long as this Sample.
  const T& data() const noexcept { return *static_cast<const T*>(data_.get()); }
  const dds_sample_info_t& info() const noexcept { return info_; }
  bool valid_data() const noexcept { return info_.valid_data; }
  /// ALIVE, NOT_ALIVE_DISPOSED (clean leave) or NOT_ALIVE_NO_WRITERS (writer lost or deleted).
  dds_instance_state_t instance_state() const noexcept { return info_.instance_state; }

 private:
  OwnedSample data_;
  dds_sample_info_t info_;
};

namespace detail {

// Untyped cores: the templates below only cast.
class WriterCore {
 public:
  WriterCore(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
             const std::string& topic_name, const Qos& qos);
  void Write(const void* sample);
  void Dispose(const void* key_sample);
  void Unregister(const void* key_sample);
  void Flush();
  uint32_t MatchedReaders() const;
  dds_entity_t handle() const noexcept { return writer_.get(); }

 private:
  std::string topic_name_;
  Entity topic_;
  Entity writer_;  // declared after topic_: deleted before it
};

class ReaderCore {
 public:
  ReaderCore(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
             const std::string& topic_name, const Qos& qos);
  using Visit = void (*)(void* context, const void* sample, const dds_sample_info_t& info);
  std::vector<std::pair<OwnedSample, dds_sample_info_t>> TakeOwned(std::size_t max_samples);
  std::size_t TakeLoaned(std::size_t max_samples, Visit visit, void* context);
  bool WaitForData(std::chrono::nanoseconds timeout);
  uint32_t MatchedWriters() const;
  dds_entity_t handle() const noexcept { return reader_.get(); }

 private:
  const dds_topic_descriptor_t* descriptor_;
  std::string topic_name_;
  Entity topic_;
  Entity reader_;
  Entity read_condition_;                  // any sample or instance-state change held by reader_
  Entity waitset_;                         // waits on read_condition_; deleted first
  std::vector<OwnedSample> free_buffers_;  // zeroed samples reused by the next TakeOwned
};

/// Polls `matched_count()` until it reaches `count` or `timeout` passes.
template <class Count>
bool WaitForMatch(Count matched_count, uint32_t count, std::chrono::milliseconds timeout);

}  // namespace detail

/// Writes messages of type T on its topic (default: MessageTraits<T>::kTopicName). Move-only.
template <class T>
class Writer {
 public:
  /// Creates a writer, with its own topic entity, in `participant` with `qos` (from qos.h).
  Writer(const Participant& participant, const Qos& qos,
         const std::string& topic_name = MessageTraits<T>::kTopicName)
      : Writer(participant.handle(), qos, topic_name) {}
  /// As above from a raw participant handle (tests pass invalid ones to check errors).
  Writer(dds_entity_t participant, const Qos& qos,
         const std::string& topic_name = MessageTraits<T>::kTopicName)
      : core_(participant, MessageTraits<T>::Descriptor(), topic_name, qos) {}

  /// Publishes `sample`; the sample is serialised during the call and not retained.
  void Write(const T& sample) { core_.Write(&sample); }
  /// Marks the instance named by the key fields of `key_sample` NOT_ALIVE_DISPOSED (clean leave).
  void Dispose(const T& key_sample) { core_.Dispose(&key_sample); }
  /// Stops writing the instance without disposing it: readers see NOT_ALIVE_NO_WRITERS.
  void Unregister(const T& key_sample) { core_.Unregister(&key_sample); }
  /// Sends what the writer holds back under write batching (WithBatchedWrites); without it a
  /// write has gone out already and this sends nothing.
  void Flush() { core_.Flush(); }
  /// Number of readers currently matched.
  uint32_t MatchedReaders() const { return core_.MatchedReaders(); }
  /// Waits until at least `count` readers are matched; false on timeout.
  bool WaitForReaders(uint32_t count, std::chrono::milliseconds timeout) const {
    return detail::WaitForMatch([this] { return MatchedReaders(); }, count, timeout);
  }
  dds_entity_t handle() const noexcept { return core_.handle(); }

 private:
  detail::WriterCore core_;
};

/// How long a node pauses between takes while it waits for a stream of many samples (a cycle's
/// vehicle states). A thread blocked in WaitForData is woken by each sample that arrives: a
/// futex wake and a context switch per state, 100,000 a second at 10,000 vehicles, paid by the
/// receive thread that must also decrypt them. A take every half millisecond collects them by
/// the hundred instead, for at most half a millisecond of latency.
inline constexpr std::chrono::microseconds kStreamPoll{500};

/// Takes messages of type T from its topic (default: MessageTraits<T>::kTopicName). Move-only;
/// use one Reader from one thread at a time (it keeps a pool of sample buffers).
template <class T>
class Reader {
 public:
  /// Creates a reader, with its own topic entity and waitset, in `participant` with `qos`.
  Reader(const Participant& participant, const Qos& qos,
         const std::string& topic_name = MessageTraits<T>::kTopicName)
      : core_(participant.handle(), MessageTraits<T>::Descriptor(), topic_name, qos) {}

  /// Takes (removes) up to `max_samples` samples, data and instance-state changes alike, each
  /// owning its memory. Allocation-light: unused buffers are kept for the next call.
  std::vector<Sample<T>> Take(std::size_t max_samples = 256) {
    std::vector<Sample<T>> samples;
    for (auto& [data, info] : core_.TakeOwned(max_samples)) {
      samples.emplace_back(std::move(data), info);
    }
    return samples;
  }

  /// Takes up to `max_samples` samples on loan and calls visit(const T&, const dds_sample_info_t&)
  /// for each, returning the loan afterwards (also if visit throws): zero copies, but the
  /// references are invalid after visit returns. Returns the number of samples visited.
  template <class Visit>
  std::size_t TakeEach(Visit&& visit, std::size_t max_samples = 256) {
    auto trampoline = [](void* context, const void* sample, const dds_sample_info_t& info) {
      (*static_cast<std::remove_reference_t<Visit>*>(context))(*static_cast<const T*>(sample), info);
    };
    return core_.TakeLoaned(max_samples, trampoline, &visit);
  }

  /// Blocks until a sample or instance-state change is ready to take; false on timeout. For one
  /// awaited sample (the server's word of a cycle); a stream of many is polled (kStreamPoll).
  bool WaitForData(std::chrono::nanoseconds timeout) { return core_.WaitForData(timeout); }
  /// Number of writers currently matched (alive or not yet timed out).
  uint32_t MatchedWriters() const { return core_.MatchedWriters(); }
  /// Waits until at least `count` writers are matched; false on timeout.
  bool WaitForWriters(uint32_t count, std::chrono::milliseconds timeout) const {
    return detail::WaitForMatch([this] { return MatchedWriters(); }, count, timeout);
  }
  dds_entity_t handle() const noexcept { return core_.handle(); }

 private:
  detail::ReaderCore core_;
};

template <class Count>
bool detail::WaitForMatch(Count matched_count, uint32_t count, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (matched_count() < count) {
    if (std::chrono::steady_clock::now() >= deadline) return false;
    dds_sleepfor(DDS_MSECS(1));
  }
  return true;
}

}  // namespace sage::proto
