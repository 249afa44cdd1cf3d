// WireBytes against Cyclone DDS's own serialised size of the same sample (dds_takecdr gives the
// sample as Cyclone received it), for every message type, with strings and sequences of lengths
// that land on each alignment (a wrong alignment or a forgotten member changes the size).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>

#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/qos.h"
#include "proto/wire_size.h"

namespace sage::proto {
namespace {

using namespace std::chrono_literals;

DomainReservation ReserveTestDomain() {
  static int test_counter = 0;
  const int preferred = 1 + (static_cast<int>(getpid()) * 37 + test_counter++ * 13) % kMaxDomainId;
  return DomainReservation::Acquire(preferred);
}

// Writes each sample and returns the size Cyclone serialised each to, in order (0 if missing).
template <class T>
std::vector<std::size_t> CycloneSizes(const std::vector<T>& samples, Qos (*qos)()) {
  const DomainReservation domain = ReserveTestDomain();
  Participant participant(domain.domain_id(), LocalhostConfigXml(4));
  Reader<T> reader(participant, qos());
  Writer<T> writer(participant, qos());
  EXPECT_TRUE(writer.WaitForReaders(1, 2s));
  std::vector<std::size_t> sizes;
  for (const T& sample : samples) {
    writer.Write(sample);
    ddsi_serdata* data = nullptr;
    dds_sample_info_t info;
    int taken = 0;
    for (int attempt = 0; attempt < 200 && taken <= 0; ++attempt) {
      reader.WaitForData(10ms);
      taken = dds_takecdr(reader.handle(), &data, 1, &info, DDS_ANY_STATE);
    }
    sizes.push_back(taken == 1 ? ddsi_serdata_size(data) : 0);
    if (taken == 1) ddsi_serdata_unref(data);
  }
  return sizes;
}

template <class T>
void ExpectSizesMatch(const std::vector<T>& samples, Qos (*qos)()) {
  const std::vector<std::size_t> cyclone = CycloneSizes(samples, qos);
  ASSERT_EQ(cyclone.size(), samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EXPECT_GT(cyclone[i], 0u) << "sample " << i << " not received";
    EXPECT_EQ(WireBytes(samples[i]), cyclone[i]) << "sample " << i;
  }
}

// Names of 0..8 characters: every remainder of the string's length modulo 8.
const std::vector<std::string> kNames = {"", "a", "ab", "abc", "abcd", "abcde", "abcdef", "abcdefg", "abcdefgh"};

Qos StateQos() { return VehicleStateReaderQos(); }

TEST(WireBytes, VehicleStateMatchesCyclone) {
  std::vector<VehicleState> samples;
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    VehicleState s{static_cast<uint32_t>(i), 1, 2, 3, {}, 1, 2, 3, 4, 5, 6, 7, 8};
    ASSERT_TRUE(CopyBounded(s.name, kNames[i]));
    samples.push_back(s);
  }
  ExpectSizesMatch(samples, &StateQos);
}

TEST(WireBytes, VehicleCoverageMatchesCyclone) {
  std::vector<std::vector<double>> sums = {{}, {1.0}, std::vector<double>(400, 0.5), std::vector<double>(1600, 0.25)};
  std::vector<VehicleCoverage> samples;
  for (std::size_t i = 0; i < sums.size(); ++i) {
    samples.push_back(VehicleCoverage{static_cast<uint32_t>(i), 1, 2.0, i, 3.0, BorrowSequence(sums[i])});
  }
  ExpectSizesMatch(samples, &VehicleCoverageQos);
}

TEST(WireBytes, ErgodicTargetMatchesCyclone) {
  const std::vector<double> phi(400, 0.1), none;
  const std::vector<int32_t> tour_odd = {3, 1, 4}, tour_even = {2, 7};
  const std::vector<double> waits_odd = {0.2, 0.3, 0.5}, waits_even = {0.5, 0.5};
  // A region target by its valves and weights (no phi), with odd and even counts.
  const std::vector<int32_t> valves_odd = {5, 9, 11}, valves_even = {0, 3};
  std::vector<ErgodicTarget> samples = {
      {0, 1, 2, 3, 20, true, BorrowSequence(phi), {}, {}, 1, 2, 3, 4, 0, 0, {}, {}},
      {1, 1, 2, 3, 20, false, BorrowSequence(none), BorrowSequence(tour_odd), BorrowSequence(waits_odd), 1, 2, 3, 4, 12, 40.5, {}, {}},
      {2, 1, 2, 3, 20, false, BorrowSequence(phi), BorrowSequence(tour_even), BorrowSequence(waits_even), 1, 2, 3, 4, 12, 0, {}, {}},
      {3, 1, 2, 3, 20, false, BorrowSequence(none), {}, {}, 1, 2, 3, 4, 12, 0, BorrowSequence(valves_odd), BorrowSequence(waits_odd)},
      {4, 1, 2, 3, 20, false, BorrowSequence(none), {}, {}, 1, 2, 3, 4, 12, 7.5, BorrowSequence(valves_even), BorrowSequence(waits_even)},
  };
  ExpectSizesMatch(samples, &ErgodicTargetQos);
}

// A batch of targets: the elements' members aligned from the payload's start, not the element's.
TEST(WireBytes, ErgodicTargetsMatchCyclone) {
  const std::vector<double> phi(3, 0.1), none, waits_odd = {0.2, 0.3, 0.5};
  const std::vector<int32_t> valves_odd = {5, 9, 11}, valves_even = {0, 3}, tour_odd = {3, 1, 4};
  const std::vector<double> weights_even = {0.5, 0.5};
  const std::vector<ErgodicTarget> elements = {
      {3, 1, 2, 3, 20, false, BorrowSequence(none), {}, {}, 1, 2, 3, 4, 12, 0, BorrowSequence(valves_odd), BorrowSequence(waits_odd)},
      {4, 1, 2, 3, 20, true, BorrowSequence(phi), BorrowSequence(tour_odd), BorrowSequence(waits_odd), 1, 2, 3, 4, 0, 7.5, {}, {}},
      {5, 1, 2, 3, 20, false, BorrowSequence(none), {}, {}, 1, 2, 3, 4, 12, 0, BorrowSequence(valves_even), BorrowSequence(weights_even)},
  };
  std::vector<ErgodicTargets> samples;
  for (std::size_t n = 0; n <= elements.size(); ++n) {
    samples.push_back({1, 2, 3, BorrowSequence(std::span<const ErgodicTarget>(elements.data(), n))});
  }
  ExpectSizesMatch(samples, &ErgodicTargetsQos);
}

TEST(WireBytes, DetectionMatchesCyclone) {
  const std::vector<std::vector<double>> xy = {{}, {1.0, 2.0}, {1.0, 2.0, 3.0, 4.0, 5.0, 6.0}};
  std::vector<Detection> samples;
  for (std::size_t i = 0; i < xy.size(); ++i) {
    samples.push_back(Detection{static_cast<uint32_t>(i), 1, 2, 3, static_cast<uint32_t>(i), 1.0, 2.0, 0.5, BorrowSequence(xy[i])});
  }
  ExpectSizesMatch(samples, &DetectionQos);
}

TEST(WireBytes, FleetCoverageMatchesCyclone) {
  const std::vector<double> phi(400, 0.1), sums(400, 0.2), weights_odd(5, 0.2), weights_even(4, 0.25);
  const std::vector<uint32_t> ids_odd = {1, 2, 3}, ids_even = {1, 2};
  const std::vector<uint64_t> seqs_odd = {4, 5, 6}, seqs_even = {4, 5};
  std::vector<FleetCoverage> samples = {
      {1, 2, 3, 4.0, 20, BorrowSequence(phi), BorrowSequence(sums), 5.0, BorrowSequence(ids_odd),
       BorrowSequence(seqs_odd), BorrowSequence(weights_odd)},
      {1, 2, 4, 4.0, 20, {}, {}, 5.0, BorrowSequence(ids_even), BorrowSequence(seqs_even),
       BorrowSequence(weights_even)},
      {1, 2, 5, 4.0, 20, {}, {}, 5.0, {}, {}, {}},
  };
  ExpectSizesMatch(samples, &FleetCoverageQos);
}

TEST(WireBytes, OperatorMessagesMatchCyclone) {
  std::vector<RiskUpdate> updates;
  std::vector<RiskUpdateResult> results;
  std::vector<FleetCommand> commands;
  std::vector<FleetCommandResult> command_results;
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    const std::string& a = kNames[i];
    const std::string& b = kNames[(i * 3) % kNames.size()];
    updates.push_back({static_cast<int64_t>(i), BorrowString(a), 1.0, BorrowString(b)});
    results.push_back({static_cast<int64_t>(i), BorrowString(a), true, 2.0, 0.5, BorrowString(b)});
    commands.push_back({static_cast<int64_t>(i), 7, BorrowString(a), 2, 3});
    command_results.push_back({static_cast<int64_t>(i), BorrowString(a), false, BorrowString(b), -1, 2, 3, 4.0});
  }
  ExpectSizesMatch(updates, &RiskUpdateQos);
  ExpectSizesMatch(results, &RiskUpdateResultQos);
  ExpectSizesMatch(commands, &FleetCommandQos);
  ExpectSizesMatch(command_results, &FleetCommandResultQos);
}

TEST(WireBytes, MissionStatusMatchesCyclone) {
  std::vector<MissionStatus> samples = {{1, 2, 3, 1.0, 4, 5.0, 6.0, 7, 8, 9.0, 10.0, true, 11}};
  ExpectSizesMatch(samples, &MissionStatusQos);
}

}  // namespace
}  // namespace sage::proto
