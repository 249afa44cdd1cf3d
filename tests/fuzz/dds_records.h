#pragma once
// DDS samples for the fuzz harnesses of the server's and the agent hosts' doors, as they reach
// the doors in a mission: CDR bytes checked and decoded by Cyclone's own deserialiser of the
// generated types (dds_stream_normalize_data, then dds_stream_read: what a reader does with a
// sample off the wire), so a harness sees exactly the C structs a hostile but authenticated
// writer can make arrive. One fuzz input is a run of records:
//
//   [op: 1 byte][flags: 1 byte][length: 2 bytes, little-endian][length bytes of CDR]
//
// `op` picks the topic (or an action of the harness: a cycle, a vehicle gone); `flags` carries
// what DDS adds to a sample (its writer, its instance state) and whether the harness stamps
// the mission's server instance on it (so that mutations explore the door rather than the one
// check of a 64-bit number). make_seeds.cpp writes records of a real in-process mission.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <vector>

extern "C" {
#include <dds/dds.h>
#include <dds/ddsi/ddsi_cdrstream.h>
}

#include "proto/messages.h"
#include "tests/fuzz/fuzz_support.h"

namespace sage::fuzz {

/// XCDR1: what Cyclone 0.10 writes for the project's final, non-optional types.
inline constexpr std::uint32_t kXcdrVersion = 1;
/// Records per input at most: each may step a mission, so an input stays well under a second.
inline constexpr std::size_t kMaxRecords = 256;

/// flags: bits 0-3 the writer (a handle 1..16), bit 4 stamp the mission's server instance,
/// bits 5-6 the instance state (0 alive, 1 disposed, 2 no writers), bit 7 not valid data.
struct Record {
  std::uint8_t op = 0;
  std::uint8_t flags = 0;
  std::span<const std::uint8_t> payload;
  std::uint64_t writer() const { return 0x100u + (flags & 0x0fu); }
  bool stamp_instance() const { return (flags & 0x10u) != 0; }
  int instance_state() const { return (flags >> 5) & 0x3; }
  bool valid_data() const { return (flags & 0x80u) == 0; }
};

/// The records of one input (a short last one takes what is left).
inline std::vector<Record> SplitRecords(const std::uint8_t* data, std::size_t size) {
  std::vector<Record> out;
  std::size_t at = 0;
  while (at + 4 <= size && out.size() < kMaxRecords) {
    Record r;
    r.op = data[at];
    r.flags = data[at + 1];
    const std::size_t length = static_cast<std::size_t>(data[at + 2]) | (static_cast<std::size_t>(data[at + 3]) << 8);
    at += 4;
    const std::size_t taken = std::min(length, size - at);
    r.payload = {data + at, taken};
    at += taken;
    out.push_back(r);
  }
  return out;
}

/// Samples decoded and handed to a door, and those Cyclone's check refused (printed at exit).
struct SampleCounts {
  std::uint64_t decoded = 0;
  std::uint64_t refused_by_cdr = 0;
};
inline SampleCounts& Counts() {
  static SampleCounts counts;
  return counts;
}
inline void PrintCountsAtExit(const char* harness) {
  static const char* name = harness;
  std::atexit([] {
    std::fprintf(stderr, "%s: %llu DDS samples decoded and handed to the door, %llu refused by Cyclone's CDR check\n",
                 name, static_cast<unsigned long long>(Counts().decoded),
                 static_cast<unsigned long long>(Counts().refused_by_cdr));
  });
}

/// One sample of a generated type decoded from CDR as a reader would: empty (ok() false) if
/// Cyclone's normaliser refuses the bytes. Frees what the decoder allocated.
template <typename T>
class Decoded {
 public:
  explicit Decoded(std::span<const std::uint8_t> cdr) {
    const std::uint32_t* ops = proto::MessageTraits<T>::Descriptor()->m_ops;
    // The normaliser works in place (byte order) and expects the stream's own alignment.
    buffer_.assign((cdr.size() + 7) / 8 + 1, 0);
    char* bytes = reinterpret_cast<char*>(buffer_.data());
    if (!cdr.empty()) std::memcpy(bytes, cdr.data(), cdr.size());
    std::uint32_t offset = 0;
    if (dds_stream_normalize_data(bytes, &offset, static_cast<std::uint32_t>(cdr.size()), false, kXcdrVersion, ops) ==
        nullptr) {
      ++Counts().refused_by_cdr;
      return;
    }
    dds_istream_t in;
    dds_istream_init(&in, static_cast<std::uint32_t>(cdr.size()), bytes, kXcdrVersion);
    std::memset(&sample_, 0, sizeof sample_);
    dds_stream_read(&in, reinterpret_cast<char*>(&sample_), ops);
    ok_ = true;
    ++Counts().decoded;
  }
  Decoded(const Decoded&) = delete;
  Decoded& operator=(const Decoded&) = delete;
  ~Decoded() {
    if (ok_) dds_stream_free_sample(&sample_, proto::MessageTraits<T>::Descriptor()->m_ops);
  }
  bool ok() const { return ok_; }
  T& get() { return sample_; }

 private:
  std::vector<std::uint64_t> buffer_;
  T sample_{};
  bool ok_ = false;
};

/// The CDR bytes of a sample (what a writer puts on the wire), for seeds.
template <typename T>
std::vector<std::uint8_t> Encode(const T& sample) {
  dds_ostream_t out;
  dds_ostream_init(&out, 0, kXcdrVersion);
  dds_stream_write(&out, reinterpret_cast<const char*>(&sample), proto::MessageTraits<T>::Descriptor()->m_ops);
  std::vector<std::uint8_t> bytes(out.m_buffer, out.m_buffer + out.m_index);
  dds_ostream_fini(&out);
  return bytes;
}

/// Appends one record to an input being built (seeds, regression inputs).
inline void AppendRecord(std::vector<std::uint8_t>& input, std::uint8_t op, std::uint8_t flags,
                         const std::vector<std::uint8_t>& payload = {}) {
  const std::size_t length = std::min<std::size_t>(payload.size(), 0xffff);
  input.push_back(op);
  input.push_back(flags);
  input.push_back(static_cast<std::uint8_t>(length & 0xff));
  input.push_back(static_cast<std::uint8_t>(length >> 8));
  input.insert(input.end(), payload.begin(), payload.begin() + static_cast<std::ptrdiff_t>(length));
}

}  // namespace sage::fuzz
