#pragma once
// The server's door to what arrives over DDS: each sample the server node takes, as the node
// hands it to the mission core (server/mission_core.h) — a vehicle's state or coverage report, an
// operator's risk update or fleet command — apart from DDS itself, so that the same code is
// tested and fuzzed without a domain (tests/fuzz). The node keeps what is about time (lockstep,
// liveliness); the door keeps who sent what and what was answered.
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <unordered_map>

#include "proto/messages.h"
#include "server/mission_core.h"

namespace sage::server {

/// What the node does with an operator's fleet command.
struct CommandOutcome {
  OperatorAnswer answer;  ///< the answer to write (FleetCommandResult)
  bool stop = false;      ///< "stop": end the mission after this cycle
  std::string stop_by;    ///< "stop": who asked, in words ("sage stop", "its launcher on a signal", ...)
  bool retire = false;    ///< "remove" accepted: order the vehicle's host to retire it
  bool repeat = false;    ///< a repeat of a command already executed: answered again, not executed
  bool ignored = false;   ///< not an operator's command (the server's own "retire", an unknown verb): no answer
};

/// Who asks a "stop", from its count (proto::StopBy), in words for the mission's record; empty for
/// a count that names no one.
std::string_view StopByWords(std::uint32_t count);

class ServerDoor {
 public:
  /// core outlives the door; server_instance: this server's (a state on another's clock is not
  /// a sample of this mission); control_rate_hz: a state's time is its cycle / rate.
  ServerDoor(MissionCore& core, std::uint64_t server_instance, double control_rate_hz)
      : core_(core), instance_(server_instance), rate_(control_rate_hz) {}

  /// A vehicle's state (a valid sample) from DDS writer `writer`: false if it is on another
  /// server's clock (sent before its host heard of this one) or the core refused it (counted
  /// under the vehicle it names and its writer). A taken state also says whether the vehicle's
  /// host has its target: one from a new writer (its host restarted: it has only what the keyed
  /// topic kept), or one still steering on an older target kTargetDueCycles after a batched one
  /// (its own target's cycle; shared and tour vehicles report the snapshot's, never older), has
  /// its target sent again, alone (MissionCore::ResendTarget).
  bool TakeState(const proto::VehicleState& m, std::uint64_t writer);
  /// A vehicle's coverage report from `writer`; false if the core refused or ignored it.
  bool TakeCoverage(const proto::VehicleCoverage& m, std::uint64_t writer);
  /// An operator's risk update from `writer` (the sender: an update cannot name another), at
  /// mission time t; refusals are logged. The answer to send, or none for a flood's refusal
  /// (one sender over its rate allowance is answered and logged at its 1st, 10th, 100th, ...
  /// refusal only: its answers would push other operators' out of the shared result topic).
  std::optional<OperatorAnswer> TakeRiskUpdate(const proto::RiskUpdate& r, std::uint64_t writer);
  /// An operator's fleet command ("reserve", "remove", "stop"; anything else is ignored). An
  /// operator sends a command again until it is answered: a repeat gets the first answer.
  CommandOutcome TakeCommand(const proto::FleetCommand& c);

  /// How vehicle `id`'s assignment of server cycle `cycle` goes out: alone (false:
  /// rt/sage/ergodic_target, keyed, transient-local, so a host that reads late still gets it) if it
  /// is the vehicle's first since it (re)joined or since its target was found missing, else in the
  /// cycle's batch (true: rt/sage/ergodic_targets). A batch is missed by a host whose reader is
  /// not matched yet, or that fell more than its depth behind; TakeState finds that from the
  /// vehicle's own word (below). Call once per assignment written.
  bool Batched(int id, std::uint64_t cycle);
  /// Targets sent again alone because a vehicle's host lacked one (TakeState).
  std::uint64_t targets_resent() const { return resent_; }
  /// Cycles after a batched target by which its vehicle must say it steers on it (its state's
  /// target_cycle), else it goes again alone. Lockstep has it there the next cycle.
  static constexpr std::int64_t kTargetDueCycles = 10;

  /// Text from outside as it may appear in a log line: at most 64 characters, control characters
  /// (newline, escape) as '?', so a sender cannot forge or break lines.
  static std::string LogSafe(std::string_view text);

 private:
  struct AnsweredCommand {
    std::int64_t stamp_ns = 0;
    std::string verb;
    std::uint32_t count = 0;
    std::uint32_t vehicle_id = 0;
    OperatorAnswer answer;
  };
  // Commands executed, kept to answer their repeats: far more than a few seconds of commands.
  static constexpr std::size_t kAnsweredKept = 256;

  MissionCore& core_;
  std::uint64_t instance_;
  double rate_;
  std::deque<AnsweredCommand> answered_;
  struct Route {
    int join = 0;                     // the join (Roster::Member::joins) its first target went alone for; -1: send alone
    std::uint64_t writer = 0;         // the DDS writer of its states (0: none yet)
    std::int64_t batched_cycle = -1;  // the cycle of its last target, if that went in a batch
  };
  std::unordered_map<int, Route> routes_;  // by vehicle id
  std::uint64_t resent_ = 0;
};

}  // namespace sage::server
