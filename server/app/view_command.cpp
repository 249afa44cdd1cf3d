#include "server/app/view_command.h"

#include <chrono>
#include <cstdio>
#include <thread>

#include <fmt/format.h>

#include "server/app/fleet_commands.h"
#include "server/live/replay.h"
#include "server/live/view_server.h"
#include "server/report/run_record.h"
#include "server/report/view_token.h"

namespace sage::server {

int CmdView(const ViewCommand& c) {
  const std::atomic<bool>* stop = StopOnSignals();
  if (c.http == "off") throw maps::ScenarioError("--http = off: sage view is nothing but its page; give a port (0: any free one)");
  const std::optional<int> port = PortOption("--http", c.http, /*off_allowed=*/false);
  const auto started = std::chrono::steady_clock::now();
  RunRecord record = ReadRunRecord(c.run_dir);
  const double read_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf("view: %s: '%s', %zu vehicle%s, %.1f s of mission%s (%zu rows read in %.1f s; poses kept every %.1f s)\n",
              c.run_dir.c_str(), record.scenario.name.c_str(), record.vehicle_names.size(),
              record.vehicle_names.size() == 1 ? "" : "s", record.end_s,
              record.complete ? "" : ", not complete (a partial record)", record.rows, read_s, record.pose_period_s);
  if (record.cut_line) std::printf("view: a last line still being written was left out\n");
  live::Replay replay(std::move(record));
  live::ViewServerOptions options;
  options.port = *port;
  options.token = NewToken();  // this page's own: another local user cannot read the record through it
  live::ViewServer server(replay, options);
  std::printf("view: open %s (Ctrl-C to stop)\n", server.Url().c_str());
  std::fflush(stdout);
  while (!stop->load()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::printf("view: stopped\n");
  return 0;
}

}  // namespace sage::server
