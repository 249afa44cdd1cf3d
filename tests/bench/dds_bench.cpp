// DDS transport figures on this machine (printed, never asserted):
//   dds_bench throughput [instances=1000] [rate_hz=10] [seconds=5] [max_participants=8]
//     two processes on loopback: keyed VehicleState, best-effort keep-last 1 per vehicle;
//     samples/s received, fraction of sent, vehicles seen, one-way latency.
//   dds_bench participants [processes=20] [max_participants=20] [unicast|multicast]
//     one participant per process on one domain: how many are created and how many each sees.
// Processes are forked before any DDS entity exists (Cyclone's threads do not survive fork).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>

#include "proto/dds_config.h"
#include "proto/dds_endpoints.h"
#include "proto/messages.h"
#include "proto/qos.h"

namespace {

using namespace sage::proto;
using Clock = std::chrono::steady_clock;

int64_t NowNs() {  // CLOCK_MONOTONIC: shared by all processes of this machine
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// Child: publishes `instances` vehicles at `rate_hz` for `seconds`; reports the count sent.
void Publish(int domain, const std::string& config, int instances, int rate_hz, int seconds,
             int report_fd) {
  Participant participant(domain, config);
  Writer<VehicleState> writer(participant, VehicleStateWriterQos());
  writer.WaitForReaders(1, std::chrono::seconds(5));
  int64_t sent = 0;
  const auto period = std::chrono::nanoseconds(1'000'000'000 / rate_hz);
  auto next = Clock::now();
  for (int tick = 0; tick < rate_hz * seconds; ++tick) {
    for (int id = 0; id < instances; ++id) {
      writer.Write(VehicleState{static_cast<uint32_t>(id), NowNs(), 0, 0, "rov", 1.0 * tick, 0, 0, 0, 0, 0, 0, 0});
      ++sent;
    }
    next += period;
    std::this_thread::sleep_until(next);
  }
  if (write(report_fd, &sent, sizeof sent) != sizeof sent) _exit(2);
}

int Throughput(int instances, int rate_hz, int seconds, int max_participants) {
  const std::string config = LocalhostConfigXml(max_participants);
  const DomainReservation domain = DomainReservation::Acquire(1 + getpid() % kMaxDomainId);
  int report[2];
  if (pipe(report) != 0) return 1;
  const pid_t child = fork();
  if (child == 0) {
    Publish(domain.domain_id(), config, instances, rate_hz, seconds, report[1]);
    _exit(0);
  }
  Participant participant(domain.domain_id(), config);
  Reader<VehicleState> reader(participant, VehicleStateReaderQos());
  int64_t received = 0;
  std::set<uint32_t> seen;
  std::vector<double> latency_ms;
  Clock::time_point first{}, last{};
  int status = 0;
  // Take until the publisher has exited and nothing is left to take.
  while (waitpid(child, &status, WNOHANG) == 0 ||
         reader.WaitForData(std::chrono::milliseconds(200))) {
    reader.WaitForData(std::chrono::milliseconds(50));
    reader.TakeEach(
        [&](const VehicleState& state, const dds_sample_info_t& info) {
          if (!info.valid_data) return;
          const auto now = Clock::now();
          if (received++ == 0) first = now;
          last = now;
          seen.insert(state.vehicle_id);
          latency_ms.push_back((NowNs() - state.stamp_ns) * 1e-6);
        },
        4096);
  }
  int64_t sent = 0;
  if (read(report[0], &sent, sizeof sent) != sizeof sent) sent = -1;
  std::sort(latency_ms.begin(), latency_ms.end());
  const double span_s = std::chrono::duration<double>(last - first).count();
  const auto pct = [&](double q) {
    return latency_ms.empty() ? 0.0
                              : latency_ms[static_cast<std::size_t>(q * (latency_ms.size() - 1))];
  };
  std::printf(
      "throughput: %d vehicles x %d Hz, %d s: sent %lld, received %lld (%.2f %%), "
      "%.0f samples/s, vehicles seen %zu, latency median %.3f ms p99 %.3f ms max %.3f ms\n",
      instances, rate_hz, seconds, static_cast<long long>(sent), static_cast<long long>(received),
      sent > 0 ? 100.0 * received / sent : 0.0, span_s > 0 ? received / span_s : 0.0, seen.size(),
      pct(0.5), pct(0.99), pct(1.0));
  return 0;
}

struct ParticipantReport {
  int created;    // 1 if the participant was created
  int seen;       // participants it discovered (itself included) before the deadline
  double seen_s;  // time until it saw them all, or the deadline
};

int Participants(int processes, int max_participants, bool multicast) {
  const std::string config =
      LocalhostConfigXml(max_participants, multicast ? LoopbackDiscovery::kMulticast
                                                     : LoopbackDiscovery::kUnicastPeers);
  const DomainReservation domain = DomainReservation::Acquire(1 + getpid() % kMaxDomainId);
  int results[2], release[2];
  if (pipe(results) != 0 || pipe(release) != 0) return 1;
  std::vector<pid_t> children;
  for (int i = 0; i < processes; ++i) {
    const pid_t child = fork();
    if (child != 0) {
      children.push_back(child);
      continue;
    }
    close(release[1]);
    ParticipantReport report{0, 0, 0.0};
    const auto start = Clock::now();
    try {
      Participant participant(domain.domain_id(), config);
      report.created = 1;
      Entity builtin(
          CheckDds(dds_create_reader(participant.handle(), DDS_BUILTIN_TOPIC_DCPSPARTICIPANT,
                                     nullptr, nullptr),
                   "dds_create_reader(DCPSParticipant)"));
      while (Clock::now() - start < std::chrono::seconds(5)) {
        void* buffers[256] = {nullptr};
        dds_sample_info_t infos[256];
        const int n = dds_read(builtin.get(), buffers, infos, 256, 256);
        if (n > 0) dds_return_loan(builtin.get(), buffers, n);
        report.seen = std::max(report.seen, n);
        report.seen_s = std::chrono::duration<double>(Clock::now() - start).count();
        if (n >= processes) break;
        dds_sleepfor(DDS_MSECS(20));
      }
      if (write(results[1], &report, sizeof report) != sizeof report) _exit(2);
      char byte;
      while (read(release[0], &byte, 1) > 0) {
      }  // stay alive until every child has reported
    } catch (const std::exception& e) {
      if (write(results[1], &report, sizeof report) != sizeof report) _exit(2);
    }
    _exit(0);
  }
  close(release[0]);
  int created = 0, min_seen = processes, max_seen = 0;
  double slowest_s = 0;
  for (int i = 0; i < processes; ++i) {
    ParticipantReport report{};
    if (read(results[0], &report, sizeof report) != sizeof report) break;
    created += report.created;
    if (report.created) {
      min_seen = std::min(min_seen, report.seen);
      max_seen = std::max(max_seen, report.seen);
      slowest_s = std::max(slowest_s, report.seen_s);
    }
  }
  close(release[1]);
  for (pid_t child : children) waitpid(child, nullptr, 0);
  std::printf(
      "participants (%s, max_participants %d): %d of %d processes created one; each saw "
      "%d..%d participants; slowest full discovery %.2f s\n",
      multicast ? "multicast on lo" : "unicast peers", max_participants, created, processes,
      min_seen, max_seen, slowest_s);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Cyclone DDS on this machine: keyed-sample throughput between two processes, and how many "
               "participants one machine fits",
               "sage_bench_dds"};
  app.require_subcommand(1);
  int instances = 1000, rate_hz = 10, seconds = 5, max_participants = 8, processes = 20, participant_slots = 20;
  bool multicast = false;
  CLI::App* throughput = app.add_subcommand("throughput", "One process publishes keyed VehicleState samples, another takes them");
  throughput->add_option("--instances", instances, "Vehicles (instances)")->capture_default_str()->check(CLI::PositiveNumber);
  throughput->add_option("--rate", rate_hz, "Samples per vehicle per second")->capture_default_str()->check(CLI::PositiveNumber);
  throughput->add_option("--seconds", seconds, "How long")->capture_default_str()->check(CLI::PositiveNumber);
  throughput->add_option("--max-participants", max_participants, "Participant indices the config allows")
      ->capture_default_str()->check(CLI::PositiveNumber);
  CLI::App* participants = app.add_subcommand("participants", "Start many participant processes; how many see each other");
  participants->add_option("--processes", processes, "Participant processes")->capture_default_str()->check(CLI::PositiveNumber);
  participants->add_option("--max-participants", participant_slots, "Participant indices the config allows")
      ->capture_default_str()->check(CLI::PositiveNumber);
  participants->add_flag("--multicast", multicast, "Discovery by multicast on lo instead of unicast peers");
  CLI11_PARSE(app, argc, argv);
  try {
    if (*throughput) return Throughput(instances, rate_hz, seconds, max_participants);
    return Participants(processes, participant_slots, multicast);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sage_bench_dds: %s\n", e.what());
    return 1;
  }
}
