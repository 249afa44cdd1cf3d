#include "proto/wire_size.h"

#include <cstdint>
#include <cstring>

namespace sage::proto {
namespace {

// Accumulates an XCDR1 payload's length member by member (offsets from the payload's start).
class Cdr {
 public:
  template <class T>
  Cdr& Primitive() {
    Align(sizeof(T));
    bytes_ += sizeof(T);
    return *this;
  }
  /// A string: its uint32 length, the characters and the terminating NUL (null = "").
  Cdr& String(const char* text) {
    Primitive<std::uint32_t>();
    bytes_ += (text != nullptr ? std::strlen(text) : 0) + 1;
    return *this;
  }
  /// A sequence of `count` elements of type T.
  template <class T>
  Cdr& Sequence(std::uint32_t count) {
    Primitive<std::uint32_t>();
    if (count > 0) {
      Align(sizeof(T));
      bytes_ += static_cast<std::size_t>(count) * sizeof(T);
    }
    return *this;
  }
  /// The sample's size: the encapsulation header and the payload, padded to a multiple of 4
  /// (RTPS keeps submessages 4-aligned; the header's options say how much is padding).
  std::size_t Total() const { return kEncapsulationHeader + (bytes_ + 3) / 4 * 4; }

 private:
  static constexpr std::size_t kEncapsulationHeader = 4;
  void Align(std::size_t to) { bytes_ = (bytes_ + to - 1) / to * to; }
  std::size_t bytes_ = 0;
};

}  // namespace

std::size_t WireBytes(const VehicleState& m) {
  Cdr c;
  c.Primitive<std::uint32_t>().Primitive<std::int64_t>().Primitive<std::uint64_t>().Primitive<std::int64_t>();
  c.String(m.name);
  for (int i = 0; i < 7; ++i) c.Primitive<double>();  // x, y, heading, vx, vy, cmd_x, cmd_y
  c.Primitive<std::uint64_t>();
  return c.Total();
}

std::size_t WireBytes(const VehicleCoverage& m) {
  Cdr c;
  c.Primitive<std::uint32_t>().Primitive<std::int64_t>().Primitive<double>().Primitive<std::uint64_t>();
  c.Primitive<double>().Sequence<double>(m.sums._length);
  return c.Total();
}

namespace {
// An ErgodicTarget's members where they fall in the payload (alone, or as an element of a batch:
// XCDR1 aligns a nested struct's members from the payload's start too).
void TargetMembers(Cdr& c, const ErgodicTarget& m) {
  c.Primitive<std::uint32_t>().Primitive<std::int64_t>().Primitive<std::uint64_t>().Primitive<std::uint64_t>();
  c.Primitive<std::uint32_t>().Primitive<bool>();
  c.Sequence<double>(m.phi._length).Sequence<std::int32_t>(m.tour._length).Sequence<double>(m.tour_weights._length);
  for (int i = 0; i < 4; ++i) c.Primitive<double>();  // the region's box
  c.Primitive<std::uint32_t>().Primitive<double>();  // its order, its forgetting
  c.Sequence<std::int32_t>(m.region_valves._length).Sequence<double>(m.region_weights._length);
}
}  // namespace

std::size_t WireBytes(const ErgodicTarget& m) {
  Cdr c;
  TargetMembers(c, m);
  return c.Total();
}

std::size_t WireBytes(const ErgodicTargets& m) {
  Cdr c;
  c.Primitive<std::int64_t>().Primitive<std::uint64_t>().Primitive<std::uint64_t>();
  c.Primitive<std::uint32_t>();  // the sequence's length
  for (std::uint32_t i = 0; i < m.targets._length; ++i) TargetMembers(c, m.targets._buffer[i]);
  return c.Total();
}

std::size_t WireBytes(const FleetCoverage& m) {
  Cdr c;
  c.Primitive<std::int64_t>().Primitive<std::uint64_t>().Primitive<std::uint64_t>().Primitive<double>();
  c.Primitive<std::uint32_t>().Sequence<double>(m.phi._length).Sequence<double>(m.sums._length);
  c.Primitive<double>().Sequence<std::uint32_t>(m.vehicle_ids._length).Sequence<std::uint64_t>(m.accounted_seq._length);
  c.Sequence<double>(m.valve_weights._length);
  return c.Total();
}

std::size_t WireBytes(const RiskUpdate& m) {
  Cdr c;
  c.Primitive<std::int64_t>().String(m.valve).Primitive<double>().String(m.source);
  return c.Total();
}

std::size_t WireBytes(const RiskUpdateResult& m) {
  Cdr c;
  c.Primitive<std::int64_t>().String(m.valve).Primitive<bool>().Primitive<double>().Primitive<double>();
  c.String(m.reason);
  return c.Total();
}

std::size_t WireBytes(const MissionStatus&) {
  Cdr c;
  c.Primitive<std::int64_t>().Primitive<std::uint64_t>().Primitive<std::int64_t>().Primitive<double>();
  c.Primitive<std::uint64_t>().Primitive<double>().Primitive<double>();
  c.Primitive<std::uint32_t>().Primitive<std::uint32_t>().Primitive<double>().Primitive<double>();
  c.Primitive<bool>().Primitive<std::uint64_t>();
  return c.Total();
}

std::size_t WireBytes(const FleetCommand& m) {
  Cdr c;
  c.Primitive<std::int64_t>().Primitive<std::uint64_t>().String(m.verb).Primitive<std::uint32_t>();
  c.Primitive<std::uint32_t>();
  return c.Total();
}

std::size_t WireBytes(const FleetCommandResult& m) {
  Cdr c;
  c.Primitive<std::int64_t>().String(m.verb).Primitive<bool>().String(m.reason).Primitive<std::int32_t>();
  c.Primitive<std::uint32_t>().Primitive<std::uint32_t>().Primitive<double>();
  return c.Total();
}

std::size_t WireBytes(const Detection& m) {
  Cdr c;
  c.Primitive<std::uint32_t>().Primitive<std::int64_t>().Primitive<std::uint64_t>().Primitive<std::int64_t>();
  c.Primitive<std::uint32_t>().Primitive<double>().Primitive<double>().Primitive<double>();
  c.Sequence<double>(m.detections_xy_m._length);
  return c.Total();
}

}  // namespace sage::proto
