#include "server/node/server_door.h"

#include <algorithm>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "agents/node/wire.h"
#include "maps/scenario/printable_text.h"
#include "server/operator_requests.h"

namespace sage::server {

std::string_view StopByWords(std::uint32_t count) {
  switch (static_cast<proto::StopBy>(count)) {
    case proto::StopBy::kOperator: return "sage stop";
    case proto::StopBy::kLauncherSignal: return "its launcher, on a signal (Ctrl-C, SIGTERM)";
    case proto::StopBy::kLauncherFleetGone: return "its launcher, every agent host gone";
  }
  return {};
}

std::string ServerDoor::LogSafe(std::string_view text) { return maps::PrintableUtf8(text, 64); }

bool ServerDoor::TakeState(const proto::VehicleState& m, std::uint64_t writer) {
  if (m.server_instance != instance_) return false;
  if (!core_.OnState(agents::wire::FromWire(m, rate_), writer)) return false;
  Route& route = routes_[static_cast<int>(m.vehicle_id)];  // its first state: join 0, no target sent yet
  const bool new_writer = route.join != 0 && route.writer != 0 && writer != route.writer;  // and a target sent
  route.writer = writer;
  const bool missing = route.batched_cycle >= 0 && m.target_cycle < static_cast<std::uint64_t>(route.batched_cycle) &&
                       m.cycle >= route.batched_cycle + kTargetDueCycles;
  if (new_writer || missing) {
    core_.ResendTarget(static_cast<int>(m.vehicle_id));
    route.join = -1;
    route.batched_cycle = -1;
    ++resent_;
  }
  return true;
}

bool ServerDoor::TakeCoverage(const proto::VehicleCoverage& m, std::uint64_t writer) {
  return core_.OnCoverage(agents::wire::FromWire(m), writer);
}

std::optional<OperatorAnswer> ServerDoor::TakeRiskUpdate(const proto::RiskUpdate& r, std::uint64_t writer) {
  // The source as the record keeps it (risk_events.csv, metrics.json): printable UTF-8.
  const std::string source = LogSafe(proto::AsStringView(r.source));
  const std::string sender = fmt::format("{} (writer {:x})", source, writer);
  if (const std::string why = RiskSourceProblem(source); !why.empty()) {
    // Refused at the door, counted with the operator's other refusals (a source of the mission's
    // own had been recorded as if the mission made the change).
    OperatorAnswer refused;
    refused.reason = fmt::format("source = {}: {}", source, why);
    spdlog::warn("server: ignored a risk update from {}: {}", LogSafe(sender), LogSafe(refused.reason));
    return refused;
  }
  const std::uint64_t limited = core_.risk_limits().refused(sender);
  const OperatorAnswer a = core_.OnRiskUpdate(std::string(proto::AsStringView(r.valve)), r.weight, source, sender);
  const std::uint64_t refused = core_.risk_limits().refused(sender);
  const bool newly_limited = refused > limited;
  // A flood's refusals are logged and answered at 1, 10, 100, ... per sender, not each: its
  // answers would crowd other operators' answers out of the shared result topic.
  const auto decade = [](std::uint64_t n) {
    while (n % 10 == 0 && n > 1) n /= 10;
    return n == 1;
  };
  if (newly_limited && !decade(refused)) return std::nullopt;
  if (!a.accepted) {
    spdlog::warn("server: ignored a risk update from {}: {}{}", sender, LogSafe(a.reason),
                 newly_limited ? fmt::format(" ({} refused so far)", refused) : "");
  }
  return a;
}

CommandOutcome ServerDoor::TakeCommand(const proto::FleetCommand& c) {
  CommandOutcome out;
  const std::string_view verb = proto::AsStringView(c.verb);
  const auto repeat = std::find_if(answered_.begin(), answered_.end(), [&](const AnsweredCommand& done) {
    return done.stamp_ns == c.stamp_ns && done.verb == verb && done.count == c.count && done.vehicle_id == c.vehicle_id;
  });
  if (repeat != answered_.end()) {
    out.answer = repeat->answer;
    out.repeat = true;
    return out;
  }
  if (verb == "stop") {
    const std::string_view by = StopByWords(c.count);
    if (by.empty()) {
      out.answer.reason = fmt::format("a stop's count says who asks (0: an operator, 1 and 2: its launcher), not {}", c.count);
    } else {
      out.answer.accepted = true;
      out.stop = true;
      out.stop_by = by;
    }
  } else if (verb == "remove") {
    out.answer = core_.RemoveRequest(static_cast<int>(c.vehicle_id));
    out.retire = out.answer.accepted;
  } else if (verb == "reserve") {
    out.answer = core_.ReserveIds(static_cast<int>(c.count));
  } else {
    // The server's own "retire" orders come back on the topic it shares with the operators: no
    // answer to those, nor to anything else that is not an operator's command.
    out.ignored = true;
    return out;
  }
  answered_.push_back({c.stamp_ns, std::string(verb), c.count, c.vehicle_id, out.answer});
  if (answered_.size() > kAnsweredKept) answered_.pop_front();
  return out;
}

bool ServerDoor::Batched(int id, std::uint64_t cycle) {
  const Roster::Member* m = core_.roster().Find(id);
  if (m == nullptr) return false;
  const auto [at, first] = routes_.try_emplace(id);
  Route& route = at->second;
  if (!first && route.join == m->joins) {
    route.batched_cycle = static_cast<std::int64_t>(cycle);
    return true;
  }
  route.join = m->joins;  // its first since it (re)joined, or since its target went missing: alone
  route.batched_cycle = -1;
  return false;
}

}  // namespace sage::server
