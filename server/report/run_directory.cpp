#include "server/report/run_directory.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <iterator>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "maps/risk_layer.h"
#include "server/report/atomic_write.h"
#include "server/report/checkpoint.h"
#include "server/report/mission_file.h"
#include "server/report/record_csv.h"

namespace sage::server {
namespace {

namespace fs = std::filesystem;

// CPU seconds the calling thread has used: what a checkpoint costs the machine, whatever else
// runs beside it.
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// One trajectory.csv row; "{}" prints the shortest text that parses back to the same double.
void AppendTrajectoryRow(std::string& out, const TrajectorySample& s, const std::string& name) {
  fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{},{},{},{}\n", s.time_s, name, s.position_m.x(),
                 s.position_m.y(), s.heading_rad, s.velocity_mps.x(), s.velocity_mps.y(), s.command_mps.x(),
                 s.command_mps.y());
}

constexpr const char* kTrajectoryHeader = "t,vehicle,x,y,heading,vx,vy,cmd_x,cmd_y\n";
constexpr const char* kFleetEventsHeader = "t,event,vehicle_id,name,detail\n";
constexpr const char* kRiskEventsHeader = "t,valve,weight,share,source\n";
constexpr const char* kRegionsHeader = "t,vehicle_id,name,x_m,y_m,width_m,height_m,order,valves\n";
// The final set besides the charts; metrics.json last, since "complete": true says the others are in place.
constexpr const char* kFinalFiles[] = {"seabed.bt", "risk.ot", "scenario.yaml", "metrics.json"};
constexpr const char* kChartFiles[] = {"plot.svg", "plot.png", "metric.svg", "metric.png", "revisits.svg", "revisits.png"};

// A CSV field for free text: quoted, inner quotes doubled, control characters as spaces, so a
// name or reason can never start a new line or a new column.
std::string Quoted(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += "\"\"";
    else out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? ' ' : c;
  }
  return out + "\"";
}

[[noreturn]] void Fail(const std::string& path, int error) {
  throw std::runtime_error(fmt::format("{}: cannot write: {}", path, std::strerror(error)));
}

// Cuts a file of lines back to its last complete line (a crash or a full disk can leave half a
// line at the end).
void CutToLastLine(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t end = text.rfind('\n');
  const std::size_t keep = end == std::string::npos ? 0 : end + 1;
  if (keep < text.size()) fs::resize_file(path, keep);
}

// The lines of a file after its header, numbered from 2.
std::vector<std::pair<int, std::string>> Lines(const std::string& path) {
  std::vector<std::pair<int, std::string>> lines;
  std::ifstream in(path);
  std::string text;
  int number = 0;
  while (std::getline(in, text)) {
    if (++number == 1 || text.empty()) continue;
    lines.emplace_back(number, text);
  }
  return lines;
}

}  // namespace

RunDirectory::RunDirectory(std::string dir, const maps::Scenario& scenario, RunDirectoryOptions options)
    : dir_(std::move(dir)),
      scenario_(scenario),
      options_(std::move(options)),
      trajectory_every_(scenario.TrajectoryEvery()),
      plot_(scenario, options_.plot_points, options_.plot_events) {
  PrepareRunDirectory(dir_);
  if (!options_.resume) {
    // A new mission: nothing of an earlier one in this directory may pass for its results.
    std::error_code ignored;
    for (const char* name : {"metrics.json", "seabed.bt", "risk.ot", kCheckpointFile}) fs::remove(fs::path(dir_) / name, ignored);
    for (const char* name : kChartFiles) fs::remove(fs::path(dir_) / name, ignored);
  }
  try {
    Open(trajectory_, "trajectory.csv", kTrajectoryHeader);
    Open(fleet_events_, "fleet_events.csv", kFleetEventsHeader);
    Open(risk_events_, "risk_events.csv", kRiskEventsHeader);
    Open(regions_, "regions.csv", kRegionsHeader);
    if (!options_.resume) WriteScenarioFile(dir_, scenario_);
  } catch (const std::runtime_error& e) {
    throw maps::ScenarioError(fmt::format("--out = {}: cannot write there: {}", dir_, e.what()));
  }
  last_flush_ = last_checkpoint_ = std::chrono::steady_clock::now();
}

RunDirectory::~RunDirectory() {
  if (checkpoint_write_.valid()) checkpoint_write_.wait();
  try {
    Flush();
  } catch (const std::exception&) {  // a destructor cannot report; Finish and Tick do
  }
  for (Appender* f : {&trajectory_, &fleet_events_, &risk_events_, &regions_})
    if (f->fd >= 0) ::close(f->fd);
}

void RunDirectory::Open(Appender& file, const char* name, const char* header) {
  file.path = (fs::path(dir_) / name).string();
  const bool append = options_.resume && fs::exists(file.path);
  if (append) CutToLastLine(file.path);
  file.fd = ::open(file.path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | (append ? O_APPEND : O_TRUNC), 0644);
  if (file.fd < 0) Fail(file.path, errno);
  if (!append) {
    file.buffer = header;
    FlushOne(file);
  }
}

bool RunDirectory::RecordedAt(double time_s) const {
  return trajectory_every_ == 1 || std::llround(time_s * scenario_.control_rate_hz) % trajectory_every_ == 0;
}

void RunDirectory::Hold(const TrajectorySample& s, const std::string& name) {
  if (s.time_s < held_time_s_) return;  // a late sample of a cycle already passed
  if (s.time_s > held_time_s_) {
    held_.clear();
    held_time_s_ = s.time_s;
  }
  held_.emplace_back(s, name);
}

void RunDirectory::WriteHeldRows() {
  CollectRows();
  if (held_.empty() || !(held_time_s_ > pending_until_s_)) return;
  for (const auto& [s, name] : held_) {
    AppendTrajectoryRow(trajectory_.buffer, s, name);
    plot_.OnSample(s, name);
  }
  pending_until_s_ = held_time_s_;
  held_.clear();
}

void RunDirectory::OnSample(const TrajectorySample& s, const std::string& name) {
  if (!RecordedAt(s.time_s)) {
    Hold(s, name);
    return;
  }
  CollectRows();
  AppendTrajectoryRow(trajectory_.buffer, s, name);
  pending_until_s_ = std::max(pending_until_s_, s.time_s);
  plot_.OnSample(s, name);
}

void RunDirectory::OnSamples(const std::vector<TrajectorySample>& samples, const std::vector<const std::string*>& names) {
  // Below this a thread would cost more than the rows (about 1 us each).
  constexpr std::size_t kRowsWorthAThread = 512;
  if (samples.size() < kRowsWorthAThread) {
    MissionRecorder::OnSamples(samples, names);
    return;
  }
  CollectRows();
  // Over DDS a cycle's batch can hold late states of the cycles before it: each sample is
  // recorded or held by its own time (Scenario::trajectory_rate_hz).
  std::vector<TrajectorySample> kept;
  std::vector<std::string> row_names;
  kept.reserve(samples.size());
  row_names.reserve(samples.size());
  for (const TrajectorySample& s : samples) {
    if (!RecordedAt(s.time_s)) {
      Hold(s, *names[s.vehicle]);
      continue;
    }
    kept.push_back(s);
    row_names.push_back(*names[s.vehicle]);
    pending_until_s_ = std::max(pending_until_s_, s.time_s);
    plot_.OnSample(s, row_names.back());
  }
  if (kept.empty()) return;
  rows_ = std::async(std::launch::async, [samples = std::move(kept), row_names = std::move(row_names)] {
    std::string rows;
    for (std::size_t i = 0; i < samples.size(); ++i) AppendTrajectoryRow(rows, samples[i], row_names[i]);
    return rows;
  });
}

void RunDirectory::CollectRows() {
  if (rows_.valid()) trajectory_.buffer += rows_.get();
}

void RunDirectory::OnFleetEvent(const FleetEventRecord& e) {
  plot_.OnFleetEvent(e);
  // Names are made safe for the record when a vehicle joins (no separators, no control
  // characters); the detail is free text.
  fmt::format_to(std::back_inserter(fleet_events_.buffer), "{},{},{},{},{}\n", e.time_s, e.what, e.vehicle_id, e.name,
                 e.detail.empty() ? std::string() : Quoted(e.detail));
}

void RunDirectory::OnRegions(double time_s, const std::vector<RegionRecord>& regions) {
  for (const RegionRecord& r : regions) {
    std::string valves;
    for (const std::string& v : r.valves) valves += (valves.empty() ? "" : " ") + v;
    fmt::format_to(std::back_inserter(regions_.buffer), "{},{},{},{},{},{},{},{},{}\n", time_s, r.vehicle_id, r.name,
                   r.box.origin_m.x(), r.box.origin_m.y(), r.box.size_m.x(), r.box.size_m.y(), r.box.order,
                   Quoted(valves));
  }
}

void RunDirectory::OnRiskEvent(const RiskEventRecord& e) {
  plot_.OnRiskEvent(e);
  fmt::format_to(std::back_inserter(risk_events_.buffer), "{},{},{},{},{}\n", e.time_s, e.valve, e.raw_weight,
                 e.new_share, Quoted(e.source));
}

namespace {
void ReadRecordEvents(const std::string& dir, double after_s, RecordTail& tail);  // below, beside ReadRecordTail
}  // namespace

void RunDirectory::RestorePlot(const std::map<int, int>& index_of_id) {
  RecordTail events;
  ReadRecordEvents(dir_, -std::numeric_limits<double>::infinity(), events);
  // A row names its vehicle; the joins say which vehicle a name was at the time (a vehicle may
  // rejoin under another name, and a name freed may be taken by another).
  std::map<std::string, int> id_of_name;
  std::size_t next_fleet = 0, next_risk = 0;
  const auto events_until = [&](double t) {
    for (; next_fleet < events.fleet_events.size() && events.fleet_events[next_fleet].time_s <= t; ++next_fleet) {
      const FleetEventRecord& e = events.fleet_events[next_fleet];
      if ((e.what == "joined" || e.what == "rejoined") && e.vehicle_id >= 0) id_of_name[e.name] = e.vehicle_id;
      plot_.OnFleetEvent(e);
    }
    for (; next_risk < events.risk_events.size() && events.risk_events[next_risk].time_s <= t; ++next_risk)
      plot_.OnRiskEvent(events.risk_events[next_risk]);
  };
  // The trajectory streamed a row at a time (a long fleet mission's file is gigabytes): only its
  // time, name and position, all the plot draws.
  const std::string path = (fs::path(dir_) / "trajectory.csv").string();
  std::ifstream in(path, std::ios::binary);
  std::string row;
  std::getline(in, row);  // the header
  for (int line = 2; std::getline(in, row); ++line) {
    std::string_view fields[4];
    std::size_t start = 0;
    for (int f = 0; f < 4; ++f) {
      const std::size_t comma = row.find(',', start);
      if (comma == std::string::npos) throw maps::ScenarioError(fmt::format("{}:{}: not a trajectory row", path, line));
      fields[f] = std::string_view(row).substr(start, comma - start);
      start = comma + 1;
    }
    TrajectorySample s;
    s.time_s = detail::NumberField(std::string(fields[0]), path, line);
    s.position_m = {detail::NumberField(std::string(fields[2]), path, line),
                    detail::NumberField(std::string(fields[3]), path, line)};
    events_until(s.time_s + 1e-9);
    const std::string name(fields[1]);
    const auto id = id_of_name.find(name);
    if (id == id_of_name.end()) continue;  // a row of a vehicle the record never joined: not drawn
    const auto index = index_of_id.find(id->second);
    if (index == index_of_id.end()) continue;
    s.vehicle = index->second;
    plot_.OnSample(s, name);
  }
  events_until(std::numeric_limits<double>::infinity());
}

void RunDirectory::FlushOne(Appender& file) {
  // One write() per flush: a process killed in between leaves whole cycles behind, not half.
  std::size_t done = 0;
  while (done < file.buffer.size()) {
    const ssize_t n = ::write(file.fd, file.buffer.data() + done, file.buffer.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) Fail(file.path, errno);
    done += static_cast<std::size_t>(n);
  }
  file.buffer.clear();
}

void RunDirectory::Flush() {
  CollectRows();
  for (Appender* f : {&trajectory_, &fleet_events_, &risk_events_, &regions_}) FlushOne(*f);
  flushed_until_s_ = pending_until_s_;
  last_flush_ = std::chrono::steady_clock::now();
}

RunInfo RunDirectory::Info(const MissionCore& core, bool complete, bool stopped_early) const {
  RunInfo info;
  info.complete = complete;
  info.planned_duration_s = scenario_.duration_s;
  info.stopped_early = stopped_early;
  const RejectionCounts refused = core.rejections();
  info.rejected_samples = refused.total();
  info.rejected_by_kind = refused.by_kind();
  info.rejected_by_sender = refused.by_sender();
  info.transport = options_.transport;
  info.resumes = options_.resumes;
  info.rate_limited_risk_updates = core.risk_limits().refused();
  info.rate_limited_by_sender = core.risk_limits().refused_by_sender();
  return info;
}

std::size_t RunDirectory::buffered_bytes() const {
  return trajectory_.buffer.size() + fleet_events_.buffer.size() + risk_events_.buffer.size() + regions_.buffer.size();
}

void RunDirectory::Tick(const MissionCore& core) {
  const auto now = std::chrono::steady_clock::now();
  if (checkpoint_write_.valid() && checkpoint_write_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    checkpoint_cost_s_ += checkpoint_write_.get();  // rethrows its error
  }
  // A periodic checkpoint waits for a cycle the trajectory records, so that the record reaches it
  // (a resumed mission restarts vehicles where the record last saw them).
  if (std::chrono::duration<double>(now - last_checkpoint_).count() >=
          std::max(options_.checkpoint_period_s, kCheckpointCostRatio * checkpoint_cost_s_) &&
      RecordedAt(core.time_s())) {
    StartCheckpoint(core, /*wait=*/false);
  } else if (std::chrono::duration<double>(now - last_flush_).count() >= options_.flush_period_s ||
             buffered_bytes() >= options_.flush_bytes) {
    Flush();  // at a cycle's end: whole cycles on disk
  }
}

void RunDirectory::Checkpoint(const MissionCore& core) {
  WriteHeldRows();  // the record reaches the checkpoint, on whichever cycle it is taken
  StartCheckpoint(core, /*wait=*/true);
  checkpoint_write_.get();
}

void RunDirectory::StartCheckpoint(const MissionCore& core, bool wait) {
  Flush();
  if (checkpoint_write_.valid()) {
    // The last one is still being written (a large fleet on a slow disk): a periodic checkpoint
    // tries again next cycle.
    if (!wait && checkpoint_write_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    checkpoint_write_.get();  // rethrows its error
  }
  last_checkpoint_ = std::chrono::steady_clock::now();
  checkpoint_time_s_ = core.time_s();
  const double copy_from = ThreadCpuSeconds();
  // Copies taken now, on the mission's thread; encoding (metrics.json of 35,000 valves took 125 ms)
  // and writing happen off it.
  std::optional<MissionCheckpoint> checkpoint;
  if (options_.resumable) checkpoint = core.Checkpoint();
  MissionMetrics metrics = core.Metrics(core.time_s());
  RunInfo partial = Info(core, false, false);
  checkpoint_cost_s_ = ThreadCpuSeconds() - copy_from;  // the writing's share is added when it ends
  checkpoint_write_ = std::async(std::launch::async, [dir = dir_, checkpoint = std::move(checkpoint),
                                                      metrics = std::move(metrics), partial = std::move(partial)] {
    const double from = ThreadCpuSeconds();
    if (checkpoint) WriteCheckpoint(dir, *checkpoint);
    detail::WriteAtomically((fs::path(dir) / "metrics.json").string(), MetricsJson(metrics, &partial));
    return ThreadCpuSeconds() - from;
  });
}

void RunDirectory::Finish(const MissionCore& core, const maps::World& world, double end_s, bool stopped_early,
                          const maps::RiskLayer* risk_layer) {
  if (checkpoint_write_.valid()) checkpoint_write_.get();
  WriteHeldRows();  // the record ends where the mission did, on a recorded cycle or not
  Flush();
  const maps::Scenario ran = stopped_early ? maps::WithDuration(scenario_, end_s) : scenario_;
  const RunInfo info = Info(core, true, stopped_early);
  const std::string title =
      fmt::format("{}: {} on '{}', {} vehicle{}, {:.0f} s", scenario_.name, ToString(core.controller()),
                  core.fleet().profile().name, core.roster().members().size(),
                  core.roster().members().size() == 1 ? "" : "s", end_s);
  const MissionMetrics metrics = core.Metrics(end_s);
  plots::MissionPlotInput plot{&scenario_, &metrics, &plot_.trajectory(), plot_.Events(), plot_.events_not_kept(), title,
                               plot_.resumed_at_s()};
  std::vector<std::string> contents, paths;
  for (plots::PlotFile& f : plots::MissionPlotFiles(plot)) {
    paths.push_back((fs::path(dir_) / f.name).string());
    contents.push_back(std::move(f.bytes));
  }
  contents.push_back(world.seabed().BinaryBytes());
  contents.push_back((risk_layer ? *risk_layer : core.risk_layer()).OtBytes());
  contents.push_back(maps::EmitScenario(WithKeptSeabedMap(ran)));  // the copy taken as the mission started
  contents.push_back(MetricsJson(metrics, &info));
  for (const char* name : kFinalFiles) paths.push_back((fs::path(dir_) / name).string());
  try {
    for (std::size_t i = 0; i < paths.size(); ++i) detail::WriteTemporary(paths[i], contents[i]);
  } catch (...) {
    for (const std::string& p : paths) std::remove((p + ".tmp").c_str());
    throw;
  }
  for (const std::string& p : paths) detail::CommitTemporary(p);
  std::error_code ignored;
  fs::remove(fs::path(dir_) / kCheckpointFile, ignored);  // complete: nothing to resume
}

namespace {

// The record's fleet and risk events after mission time after_s, into `tail` (the files cut back
// to their last complete line first).
void ReadRecordEvents(const std::string& dir, double after_s, RecordTail& tail) {
  // Both files are rows of five fields, the time first: each row after after_s to `take`.
  const auto rows_after = [&](const char* name, const auto& take) {
    const std::string path = (fs::path(dir) / name).string();
    CutToLastLine(path);
    for (const auto& [line, text] : Lines(path)) {
      const std::vector<std::string> f = detail::SplitCsvLine(text);
      if (f.size() != 5) throw maps::ScenarioError(fmt::format("{}:{}: {} fields, need 5", path, line, f.size()));
      const double t = detail::NumberField(f[0], path, line);
      if (t > after_s) take(t, f, path, line);
    }
  };
  rows_after("fleet_events.csv", [&](double t, const std::vector<std::string>& f, const std::string& path, int line) {
    tail.fleet_events.push_back({t, f[1], static_cast<int>(detail::NumberField(f[2], path, line)), f[3], f[4]});
  });
  rows_after("risk_events.csv", [&](double t, const std::vector<std::string>& f, const std::string& path, int line) {
    tail.risk_events.push_back({t, f[1], detail::NumberField(f[2], path, line), detail::NumberField(f[3], path, line), f[4]});
  });
}

}  // namespace

RecordTail ReadRecordTail(const std::string& dir, double after_s) {
  RecordTail tail;
  const std::string trajectory = (fs::path(dir) / "trajectory.csv").string();
  CutToLastLine(trajectory);
  for (const auto& [line, text] : Lines(trajectory)) {
    // Only the rows after the checkpoint are parsed; the time is the first field.
    const std::size_t comma = text.find(',');
    if (comma == std::string::npos) throw maps::ScenarioError(fmt::format("{}:{}: not a trajectory row", trajectory, line));
    if (detail::NumberField(text.substr(0, comma), trajectory, line) <= after_s) continue;
    const std::vector<std::string> f = detail::SplitCsvLine(text);
    if (f.size() != 9) throw maps::ScenarioError(fmt::format("{}:{}: {} fields, need 9", trajectory, line, f.size()));
    std::vector<double> v;
    for (std::size_t i : {0, 2, 3, 4, 5, 6, 7, 8}) v.push_back(detail::NumberField(f[i], trajectory, line));
    TrajectorySample s;
    s.time_s = v[0];
    s.position_m = {v[1], v[2]};
    s.heading_rad = v[3];
    s.velocity_mps = {v[4], v[5]};
    s.command_mps = {v[6], v[7]};
    tail.samples.emplace_back(s, f[1]);
  }
  ReadRecordEvents(dir, after_s, tail);
  return tail;
}

}  // namespace sage::server
