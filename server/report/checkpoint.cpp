#include "server/report/checkpoint.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "server/report/atomic_write.h"

namespace sage::server {
namespace {

using Json = nlohmann::json;
constexpr int kFormatVersion = 3;  // 2: visit arming as each vehicle's disarmed valves; 3: the scans' expected detection

// Doubles as raw bytes (CBOR byte string): exact and a third of a text encoding's size.
Json Doubles(const double* data, std::size_t count) {
  std::vector<std::uint8_t> bytes(count * sizeof(double));
  if (count > 0) std::memcpy(bytes.data(), data, bytes.size());
  return Json::binary(std::move(bytes));
}
Json Doubles(const Eigen::VectorXd& v) { return Doubles(v.data(), static_cast<std::size_t>(v.size())); }
Json Doubles(const std::vector<double>& v) { return Doubles(v.data(), v.size()); }
std::vector<double> ToDoubles(const Json& j) {
  const auto& bytes = j.get_binary();
  if (bytes.size() % sizeof(double) != 0) throw std::invalid_argument("a number array of odd length");
  std::vector<double> out(bytes.size() / sizeof(double));
  if (!out.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
  return out;
}
Eigen::VectorXd ToVector(const Json& j) {
  const std::vector<double> d = ToDoubles(j);
  return Eigen::Map<const Eigen::VectorXd>(d.data(), static_cast<Eigen::Index>(d.size()));
}
Json Vec2(const Eigen::Vector2d& v) { return Json::array({v.x(), v.y()}); }
Eigen::Vector2d ToVec2(const Json& j) { return {j.at(0).get<double>(), j.at(1).get<double>()}; }

Json Sample(const TrajectorySample& s) {
  return {{"t", s.time_s}, {"v", s.vehicle}, {"p", Vec2(s.position_m)}, {"h", s.heading_rad},
          {"vel", Vec2(s.velocity_mps)}, {"cmd", Vec2(s.command_mps)}};
}
TrajectorySample ToSample(const Json& j) {
  return {j.at("t").get<double>(), j.at("v").get<int>(), ToVec2(j.at("p")), j.at("h").get<double>(),
          ToVec2(j.at("vel")), ToVec2(j.at("cmd"))};
}

Json Schedule(const std::vector<WeightChange>& schedule) {
  Json out = Json::array();
  for (const WeightChange& c : schedule) out.push_back({{"t", c.time_s}, {"w", Doubles(c.weights)}});
  return out;
}
std::vector<WeightChange> ToSchedule(const Json& j) {
  std::vector<WeightChange> out;
  for (const Json& c : j) out.push_back({c.at("t").get<double>(), ToVector(c.at("w"))});
  return out;
}

Json Report(const maps::CoverageReport& r) {
  return {{"seq", r.seq}, {"stamp_s", r.stamp_s}, {"kernel_s", r.kernel_time_s}, {"sums", Doubles(r.sums)}};
}
maps::CoverageReport ToReport(const Json& j) {
  return {j.at("seq").get<std::uint64_t>(), j.at("stamp_s").get<double>(), j.at("kernel_s").get<double>(),
          ToVector(j.at("sums"))};
}

Json FleetJson(const FleetServer::State& f) {
  Json responses = Json::array();
  for (const EventResponse& r : f.responses) {
    responses.push_back({{"t", r.time_s}, {"valve", r.valve}, {"w", r.new_weight}, {"turn", r.heading_change_rad}});
  }
  Json vehicles = Json::array();
  for (const auto& [id, v] : f.vehicles) {
    vehicles.push_back({{"id", id}, {"name", v.name}, {"alive", v.alive}, {"reported", v.reported},
                        {"report", Report(v.report)}, {"p", Vec2(v.position_m)}});
  }
  return {{"raw", Doubles(f.raw_weights)}, {"schedule", Schedule(f.schedule)}, {"responses", responses},
          {"next_event", f.next_event}, {"vehicles", vehicles}, {"t", f.time_s}};
}
FleetServer::State ToFleet(const Json& j) {
  FleetServer::State f;
  f.raw_weights = ToVector(j.at("raw"));
  f.schedule = ToSchedule(j.at("schedule"));
  for (const Json& r : j.at("responses")) {
    EventResponse e;
    e.time_s = r.at("t").get<double>();
    e.valve = r.at("valve").get<std::string>();
    e.new_weight = r.at("w").get<double>();
    e.heading_change_rad = r.at("turn").is_number() ? r.at("turn").get<double>() : std::nan("");
    f.responses.push_back(e);
  }
  f.next_event = j.at("next_event").get<std::size_t>();
  for (const Json& v : j.at("vehicles")) {
    FleetServer::Vehicle vehicle;
    vehicle.name = v.at("name").get<std::string>();
    vehicle.alive = v.at("alive").get<bool>();
    vehicle.reported = v.at("reported").get<bool>();
    vehicle.report = ToReport(v.at("report"));
    vehicle.position_m = ToVec2(v.at("p"));
    f.vehicles[v.at("id").get<int>()] = std::move(vehicle);
  }
  f.time_s = j.at("t").get<double>();
  return f;
}

Json RosterJson(const Roster::State& r) {
  Json members = Json::array();
  for (const auto& [id, m] : r.members) {
    const agents::StateReport& s = m.last;
    members.push_back({{"id", id}, {"name", m.name}, {"index", m.index}, {"status", static_cast<int>(m.status)},
                       {"joined_s", m.joined_s}, {"gone_s", m.gone_s}, {"has_state", m.has_state},
                       {"recorded_cycle", m.recorded_cycle}, {"cycle", s.cycle}, {"t", s.time_s},
                       {"p", Vec2(s.state.position_m)}, {"vel", Vec2(s.state.velocity_mps)},
                       {"h", s.state.heading_rad}, {"cmd", Vec2(s.command_mps)}, {"target_cycle", s.target_cycle}});
  }
  return {{"members", members}, {"next_id", r.next_id}, {"lost", r.lost_count}};
}
Roster::State ToRoster(const Json& j) {
  Roster::State r;
  for (const Json& m : j.at("members")) {
    Roster::Member member;
    member.id = m.at("id").get<int>();
    member.name = m.at("name").get<std::string>();
    member.index = m.at("index").get<int>();
    const int status = m.at("status").get<int>();
    if (status < 0 || status > 2) throw std::invalid_argument("a vehicle status out of range");
    member.status = static_cast<Roster::Status>(status);
    member.joined_s = m.at("joined_s").get<double>();
    member.gone_s = m.at("gone_s").get<double>();
    member.has_state = m.at("has_state").get<bool>();
    member.recorded_cycle = m.at("recorded_cycle").get<std::int64_t>();
    agents::StateReport& s = member.last;
    s.id = member.id;
    s.name = member.name;
    s.cycle = m.at("cycle").get<std::int64_t>();
    s.time_s = m.at("t").get<double>();
    s.state.position_m = ToVec2(m.at("p"));
    s.state.velocity_mps = ToVec2(m.at("vel"));
    s.state.heading_rad = m.at("h").get<double>();
    s.command_mps = ToVec2(m.at("cmd"));
    s.target_cycle = m.at("target_cycle").get<std::uint64_t>();
    r.members[member.id] = std::move(member);
  }
  r.next_id = j.at("next_id").get<int>();
  r.lost_count = j.at("lost").get<std::size_t>();
  return r;
}

Json MetricsStateJson(const MetricsAccumulator::State& m) {
  Json pending = Json::array();
  for (const auto& [v, s] : m.pending) pending.push_back(Sample(s));
  Json held = Json::array();
  for (const auto& [v, h] : m.last_held) {
    held.push_back({{"v", v}, {"t", h.time_s}, {"end", h.end_s}, {"p", Vec2(h.position_m)}});
  }
  Json spacings = Json::array();
  for (const auto& [dt, count] : m.spacings) spacings.push_back({dt, count});
  Json over_time = Json::array();
  for (const MetricSample& s : m.metric_over_time) over_time.push_back({s.time_s, s.ergodic_metric});
  return {{"pending", pending}, {"held", held}, {"spacings", spacings}, {"near", Doubles(m.time_near_s)},
          {"watched", Doubles(m.watched_until_s)}, {"unwatched_max", Doubles(m.longest_unwatched_s)},
          {"unwatched_sq", Doubles(m.unwatched_squares_s2)},
          {"outside", m.time_outside_s}, {"pinned", m.time_pinned_s}, {"sum_f", Doubles(m.sum_f)},
          {"sum_dt", m.sum_dt}, {"over_time", over_time}, {"metric_stride", m.metric_stride},
          {"latest_metric", m.latest_metric}, {"next_checkpoint", m.next_checkpoint},
          {"schedule", Schedule(m.schedule)}, {"refused", m.refused}};
}
MetricsAccumulator::State ToMetrics(const Json& j) {
  MetricsAccumulator::State m;
  for (const Json& s : j.at("pending")) {
    const TrajectorySample sample = ToSample(s);
    m.pending[sample.vehicle] = sample;
  }
  for (const Json& h : j.at("held")) {
    m.last_held[h.at("v").get<int>()] = {h.at("t").get<double>(), h.at("end").get<double>(), ToVec2(h.at("p"))};
  }
  for (const Json& s : j.at("spacings")) m.spacings[s.at(0).get<double>()] = s.at(1).get<std::size_t>();
  m.time_near_s = ToDoubles(j.at("near"));
  m.watched_until_s = ToDoubles(j.at("watched"));
  m.longest_unwatched_s = ToDoubles(j.at("unwatched_max"));
  m.unwatched_squares_s2 = ToDoubles(j.at("unwatched_sq"));
  m.time_outside_s = j.at("outside").get<double>();
  m.time_pinned_s = j.at("pinned").get<double>();
  m.sum_f = ToVector(j.at("sum_f"));
  m.sum_dt = j.at("sum_dt").get<double>();
  for (const Json& s : j.at("over_time")) m.metric_over_time.push_back({s.at(0).get<double>(), s.at(1).get<double>()});
  m.next_checkpoint = j.at("next_checkpoint").get<int>();
  // Older checkpoints kept every sample of the metric, and their latest was the last kept.
  m.metric_stride = j.value("metric_stride", 1);
  m.latest_metric = j.contains("latest_metric") && j.at("latest_metric").is_number() ? j.at("latest_metric").get<double>()
                    : m.metric_over_time.empty() ? std::numeric_limits<double>::quiet_NaN()
                                                 : m.metric_over_time.back().ergodic_metric;
  m.schedule = ToSchedule(j.at("schedule"));
  m.refused = j.at("refused").get<std::size_t>();
  return m;
}

Json VisitsJson(const std::vector<VisitTracker::ValveVisits>& visits) {
  Json out = Json::array();
  for (const VisitTracker::ValveVisits& v : visits) {
    out.push_back({{"n", v.count}, {"first", v.first_s}, {"folded_last", v.folded_last_s},
                   {"folded_gap", v.folded_max_gap_s}, {"recent", Doubles(v.recent)}});
  }
  return out;
}
std::vector<VisitTracker::ValveVisits> ToVisits(const Json& j) {
  std::vector<VisitTracker::ValveVisits> out;
  for (const Json& v : j) {
    VisitTracker::ValveVisits visits;
    visits.count = v.at("n").get<std::size_t>();
    visits.first_s = v.at("first").get<double>();
    visits.folded_last_s = v.at("folded_last").get<double>();
    visits.folded_max_gap_s = v.at("folded_gap").get<double>();
    visits.recent = ToDoubles(v.at("recent"));
    out.push_back(std::move(visits));
  }
  return out;
}
Json WatchesJson(const std::vector<VisitTracker::EventWatch>& watches) {
  Json out = Json::array();
  for (const VisitTracker::EventWatch& w : watches) {
    out.push_back({{"valve", w.valve}, {"t", w.time_s}, {"before", w.before}, {"after", w.after},
                   {"last_before", w.last_before_s}, {"first_after", w.first_after_s}, {"last_after", w.last_after_s}});
  }
  return out;
}
std::vector<VisitTracker::EventWatch> ToWatches(const Json& j) {
  std::vector<VisitTracker::EventWatch> out;
  for (const Json& w : j) {
    out.push_back({w.at("valve").get<int>(), w.at("t").get<double>(), w.at("before").get<std::size_t>(),
                   w.at("after").get<std::size_t>(), w.at("last_before").get<double>(),
                   w.at("first_after").get<double>(), w.at("last_after").get<double>()});
  }
  return out;
}

// The risk loop: the leak belief's leaves, the scans waiting for their cycle, the scoring.
// The expected detection's four numbers a valve (server/perception/expected_detection.h).
Json WaitsJson(const ExpectedDetection::State& w) {
  return {{"sums", Doubles(w.wait_sums)}, {"undetected", Doubles(w.undetected_s)},
          {"moment", Doubles(w.undetected_onset_s2)}, {"last", Doubles(w.last_look_s)}};
}
ExpectedDetection::State ToWaits(const Json& j) {
  ExpectedDetection::State w;
  w.wait_sums = ToDoubles(j.at("sums"));
  w.undetected_s = ToDoubles(j.at("undetected"));
  w.undetected_onset_s2 = ToDoubles(j.at("moment"));
  w.last_look_s = ToDoubles(j.at("last"));
  return w;
}

Json RiskLoopJson(const RiskLoop::State& r) {
  Json belief = Json::array();
  for (const LeakBelief::Entry& e : r.belief) belief.push_back({e.cell.i, e.cell.j, e.evidence, e.time_s});
  Json held = Json::array();
  for (const agents::ScanReport& scan : r.held) {
    std::vector<double> xy;
    for (const Eigen::Vector2d& z : scan.detections_m) xy.insert(xy.end(), {z.x(), z.y()});
    held.push_back({{"id", scan.id}, {"cycle", scan.cycle}, {"t", scan.time_s}, {"sensor", scan.sensor},
                    {"p", Vec2(scan.position_m)}, {"h", scan.heading_rad}, {"z", Doubles(xy)}});
  }
  Json last = Json::array();
  for (const auto& [key, cycle] : r.last_fused) last.push_back({key.first, key.second, cycle});
  Json leaks = Json::array();
  for (const RiskLoop::LeakTrack& l : r.leaks) {
    leaks.push_back({std::isnan(l.detected_s) ? Json(nullptr) : Json(l.detected_s),
                     std::isnan(l.confirmed_s) ? Json(nullptr) : Json(l.confirmed_s), l.detections});
  }
  Json alarms = Json::array();
  for (const RiskLoop::Alarm& a : r.alarms) {
    alarms.push_back({{"p", Vec2(a.anchor_m)}, {"raised", a.raised_s}, {"cleared", a.cleared_s},
                      {"confirmed", a.confirmed}, {"leak", a.leak}});
  }
  Json written = Json::array();
  for (const auto& [cell, value] : r.written) written.push_back({cell.i, cell.j, value});
  Json out = {{"belief", belief}, {"held", held}, {"last_fused", last}, {"leaks", leaks}, {"alarms", alarms},
              {"false_detections", r.false_detections}, {"scans", r.scans}, {"written", written},
              {"scan_waits", WaitsJson(r.scan_waits)}};
  if (!r.look_waits.last_look_s.empty()) out["look_waits"] = WaitsJson(r.look_waits);
  return out;
}
RiskLoop::State ToRiskLoop(const Json& j) {
  RiskLoop::State r;
  for (const Json& e : j.at("belief")) {
    r.belief.push_back({{e.at(0).get<int>(), e.at(1).get<int>()}, e.at(2).get<double>(), e.at(3).get<double>()});
  }
  for (const Json& h : j.at("held")) {
    agents::ScanReport scan;
    scan.id = h.at("id").get<int>();
    scan.cycle = h.at("cycle").get<std::int64_t>();
    scan.time_s = h.at("t").get<double>();
    scan.sensor = h.at("sensor").get<int>();
    scan.position_m = ToVec2(h.at("p"));
    scan.heading_rad = h.at("h").get<double>();
    const std::vector<double> xy = ToDoubles(h.at("z"));
    for (std::size_t k = 0; k + 1 < xy.size(); k += 2) scan.detections_m.emplace_back(xy[k], xy[k + 1]);
    r.held.push_back(std::move(scan));
  }
  for (const Json& l : j.at("last_fused")) r.last_fused[{l.at(0).get<int>(), l.at(1).get<int>()}] = l.at(2).get<std::int64_t>();
  const auto time_or_nan = [](const Json& t) { return t.is_null() ? std::nan("") : t.get<double>(); };
  for (const Json& l : j.at("leaks")) r.leaks.push_back({time_or_nan(l.at(0)), time_or_nan(l.at(1)), l.at(2).get<int>()});
  for (const Json& a : j.at("alarms")) {
    RiskLoop::Alarm alarm;
    alarm.anchor_m = ToVec2(a.at("p"));
    alarm.raised_s = a.at("raised").get<double>();
    alarm.cleared_s = a.at("cleared").get<double>();
    alarm.confirmed = a.at("confirmed").get<bool>();
    alarm.leak = a.at("leak").get<int>();
    r.alarms.push_back(alarm);
  }
  r.false_detections = j.at("false_detections").get<int>();
  r.scans = j.at("scans").get<std::uint64_t>();
  for (const Json& w : j.at("written")) r.written.push_back({{w.at(0).get<int>(), w.at(1).get<int>()}, w.at(2).get<float>()});
  r.scan_waits = ToWaits(j.at("scan_waits"));
  if (j.contains("look_waits")) r.look_waits = ToWaits(j.at("look_waits"));
  return r;
}

}  // namespace

std::vector<std::uint8_t> EncodeCheckpoint(const MissionCheckpoint& c) {
  const Json j = {{"format", "sage-checkpoint"}, {"version", kFormatVersion}, {"scenario_hash", c.scenario_hash},
                  {"profile", c.profile}, {"controller", c.controller}, {"cycle", c.cycle}, {"t", c.time_s},
                  {"fleet", FleetJson(c.fleet)}, {"roster", RosterJson(c.roster)}, {"metrics", MetricsStateJson(c.metrics)},
                  {"disarmed", c.disarmed}, {"visits", VisitsJson(c.visits)},
                  {"visit_watches", WatchesJson(c.visit_watches)}, {"rejected", c.rejected_samples},
                  {"rejected_by_kind", c.rejected_by_kind}, {"rejected_by_sender", c.rejected_by_sender},
                  {"risk_layer_ot", Json::binary(std::vector<std::uint8_t>(c.risk_layer_ot.begin(), c.risk_layer_ot.end()))},
                  {"risk_loop", RiskLoopJson(c.risk_loop)}};
  return Json::to_cbor(j);
}

MissionCheckpoint DecodeCheckpoint(const std::vector<std::uint8_t>& bytes, const std::string& source) {
  try {
    const Json j = Json::from_cbor(bytes);
    if (j.at("format").get<std::string>() != "sage-checkpoint" || j.at("version").get<int>() != kFormatVersion) {
      throw std::invalid_argument("not a checkpoint of this version of sage");
    }
    MissionCheckpoint c;
    c.scenario_hash = j.at("scenario_hash").get<std::uint64_t>();
    c.profile = j.at("profile").get<std::string>();
    c.controller = j.at("controller").get<std::string>();
    c.cycle = j.at("cycle").get<std::int64_t>();
    c.time_s = j.at("t").get<double>();
    c.fleet = ToFleet(j.at("fleet"));
    c.roster = ToRoster(j.at("roster"));
    c.metrics = ToMetrics(j.at("metrics"));
    c.disarmed = j.at("disarmed").get<std::vector<std::vector<int>>>();
    if (j.contains("visits")) {
      c.visits = ToVisits(j.at("visits"));
      c.visit_watches = ToWatches(j.at("visit_watches"));
    } else {
      // An older checkpoint kept every visit time: the record as the tracker keeps it now.
      for (const Json& v : j.at("visit_times")) {
        VisitTracker::ValveVisits visits;
        for (const double t : ToDoubles(v)) visits.Add(t);
        c.visits.push_back(std::move(visits));
      }
    }
    c.rejected_samples = j.at("rejected").get<std::size_t>();
    if (j.contains("rejected_by_kind")) {  // older checkpoints have the total only
      c.rejected_by_kind = j.at("rejected_by_kind").get<std::map<std::string, std::size_t>>();
      c.rejected_by_sender = j.at("rejected_by_sender").get<std::map<std::string, std::size_t>>();
    }
    if (j.contains("risk_loop")) {  // older checkpoints: no risk loop, the layer the prior alone
      const auto& ot = j.at("risk_layer_ot").get_binary();
      c.risk_layer_ot.assign(ot.begin(), ot.end());
      c.risk_loop = ToRiskLoop(j.at("risk_loop"));
    }
    return c;
  } catch (const Json::parse_error& e) {
    // Written whole and renamed into place: a file cut short was altered or copied in part since.
    throw maps::ScenarioError(fmt::format("{}: not a readable checkpoint: cut short or damaged at byte {} of {} (a "
                                          "server writes it whole; copy the run directory again, or start the mission "
                                          "anew)",
                                          source, std::min<std::size_t>(e.byte, bytes.size()), bytes.size()));
  } catch (const std::exception& e) {  // nlohmann's type and out-of-range errors: a field missing or mistyped
    throw maps::ScenarioError(fmt::format("{}: not a readable checkpoint: a field missing or of the wrong type ({}): "
                                          "damaged, or not written by this sage",
                                          source, e.what()));
  }
}

void WriteCheckpoint(const std::string& dir, const MissionCheckpoint& checkpoint) {
  const std::vector<std::uint8_t> bytes = EncodeCheckpoint(checkpoint);
  detail::WriteAtomically((std::filesystem::path(dir) / kCheckpointFile).string(),
                          std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

MissionCheckpoint ReadCheckpoint(const std::string& dir) {
  const std::string path = (std::filesystem::path(dir) / kCheckpointFile).string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw maps::ScenarioError(path + ": no checkpoint there: the mission cannot be resumed from this directory");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return DecodeCheckpoint(bytes, path);
}

}  // namespace sage::server
