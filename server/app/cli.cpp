// The `sage` command line: every subcommand and option is declared here, the only file that
// sees CLI11 (it costs seconds of compile time per file that includes it); the commands
// themselves take plain option structs (server/app/options.h).
#include "server/app/cli.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <string>
#include <system_error>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include "server/app/bench_leaks.h"
#include "server/app/bench_scale.h"
#include "server/app/field_command.h"
#include "server/app/fleet_commands.h"
#include "server/app/launch.h"
#include "server/app/operators.h"
#include "server/app/options.h"
#include "server/app/processes.h"
#include "server/app/run_commands.h"
#include "server/app/security_command.h"
#include "server/app/view_command.h"
#include "server/operator_requests.h"
#include "maps/scenario/duration_rule.h"
#include "proto/dds_config.h"
#include "proto/mission_clock.h"
#include "server/report/view_token.h"

namespace sage::server {
namespace {

enum class OverrideSet {
  kMission,   // all of them: run, compare, launch, server
  kVehicles,  // what shapes the vehicles' own control (agent hosts)
};


// Who says a risk changes, as the server's log and risk_events.csv name them: a name, not empty
// nor a line of its own (an empty one had been logged as "set to 4 by  at t = 3.6 s").
std::string MustBeASourceName(const std::string& text) {
  const bool printable =
      std::all_of(text.begin(), text.end(), [](char c) { return static_cast<unsigned char>(c) >= 0x20 && c != 0x7f; });
  if (!text.empty() && text.size() <= 64 && printable) return RiskSourceProblem(text);
  return "must be 1 to 64 characters, none a control character (who says so, e.g. 'leak detector 3')";
}

// A mission clock every agent host follows (proto::PlausibleClock refuses any other).
std::string MustBeTimeScale(const std::string& text) {
  try {
    const double scale = std::stod(text);
    if (scale >= proto::kMinTimeScale && scale <= proto::kMaxTimeScale) return {};
  } catch (const std::exception&) {
  }
  return "must be a number in 0.001..1000";
}

// A refusal that echoes what was typed, as the scenario's do ("--duration = -5: ..."): CLI11 puts
// "OPTION: " before a check's message, and InOurWords joins the two ("--weight-exponent = 9: ...").
std::string Echoed(const std::string& text, const std::string& problem) {
  return problem.empty() ? problem : "= " + text + ": " + problem;
}

// CLI11's PositiveNumber prints the whole range of a double; users need "--x = nan: must be > 0".
std::string MustBePositive(const std::string& text) {
  try {
    const double value = std::stod(text);
    return value > 0.0 ? std::string() : Echoed(text, "must be > 0");  // NaN too
  } catch (const std::exception&) {
    return Echoed(text, "must be a number > 0");
  }
}

std::optional<double> NumberIn(const std::string& text);

// A mission's length as a scenario's duration_s may be: "--duration = 1e9: must be > 0 and <= ...".
std::string MustBeADuration(const std::string& text) {
  const std::optional<double> value = NumberIn(text);
  return Echoed(text, value ? maps::DurationRangeProblem(*value) : maps::DurationRangeProblem(-1.0));
}

// A check of a number option's range, in the project's words (RangeProblem).
CLI::Validator MustBeIn(double low, double high, bool whole = false) {
  return CLI::Validator([=](std::string& text) { return Echoed(text, RangeProblem(text, low, high, whole)); },
                        whole ? fmt::format("{}..{}", low, high) : fmt::format("[{}, {}]", low, high));
}

// CLI11 reads "-3" into an unsigned option as 2^64 - 3, and a number past 2^64 - 1 as 2^64 - 1; a
// seed is a whole number as typed that fits in 64 bits, as the scenario's seed: must be.
std::string MustBeWholeNumber(const std::string& text) {
  const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
  std::uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return digits && error == std::errc() && end == text.data() + text.size()
             ? std::string()
             : Echoed(text, "must be a whole number >= 0 (at most 18446744073709551615)");
}

// `-o ""` had been read as "not given" (the default run directory, whose run it replaced).
std::string MustBeAPath(const std::string& text) {
  return text.empty() ? Echoed("\"\"", "must be a path") : std::string();
}
// ... of an option with a default: how to get it.
std::string MustBeAPathOrLeftOut(const std::string& text) {
  return text.empty() ? Echoed("\"\"", "must be a path (leave the option out for the default)") : std::string();
}

void AddScenarioOverrides(CLI::App& cmd, ScenarioOverrides& o, OverrideSet set, const std::string& example_scenario,
                          bool scenario_required = true) {
  const bool mission = set == OverrideSet::kMission;
  CLI::Option* positional = cmd.add_option("scenario", o.scenario_path, "Scenario YAML (e.g. " + example_scenario + ")");
  if (scenario_required) positional->required();
  cmd.add_option("--vehicles,-n", o.vehicles,
                 "Fleet size: the scenario's first N vehicles, or more at free starts (default: the scenario's)");
  if (mission) {
    cmd.add_option("--profile,-p", o.profile, "Risk profile named in the scenario (default: its default_profile)");
    cmd.add_option("--duration", o.duration_s, "Mission length in seconds (default: the scenario's)");
    cmd.add_option("--assignment", o.assignment,
                   "Fleet coverage: shared (Mathew-Mezic, one basis over the field), partition (valves split among "
                   "vehicles) or regions (each vehicle's share of the valves in a box with a basis of its own)")
        ->check(CLI::IsMember({"shared", "partition", "regions"}));
    cmd.add_option("--order", o.order,
                   "The A* vehicles' (-c astar) next valves: shortest (the closed tour, lap after lap: the operator's "
                   "baseline) or looks (chosen on the scans, where a leak would wait longest unseen; needs sensors) "
                   "(default: the scenario's astar.order)")
        ->check(CLI::IsMember({"shortest", "looks"}));
    cmd.add_option("--weight-exponent", o.weight_exponent,
                   "Target shaping alpha: vehicles aim for visit rates by w^alpha (1 = by risk, the paper; 0.5 = the "
                   "square-root law, least expected time a leak goes unnoticed); sets ergodic and A* alike")
        ->check(MustBeIn(0.0, maps::kMaxWeightExponent));
    cmd.add_option("--age-weighting", o.age_weighting_laps,
                   "Regions: a valve weighs w (1 + age / (L lap)) in its region's target, age the time since its last "
                   "visit (L laps of its region's tour; default: the scenario's, 1; 0 = the weights alone)")
        ->check(MustBeIn(0.0, 100.0));
    cmd.add_option("--risk-share", o.risk_share,
                   "Regions: the split balances lap x (1 + beta n W), W a region's share of the field's risk, so the "
                   "riskier valves come in smaller regions (default: the scenario's, 0.5; 0 = laps alone)")
        ->check(MustBeIn(0.0, 10.0));
    cmd.add_option("--trajectory-rate", o.trajectory_rate_hz,
                   "trajectory.csv's rows a vehicle per mission second: the control rate over a whole number (a row "
                   "every k-th cycle), 0 = every cycle (default: the scenario's trajectory_rate_hz; generated fields "
                   "of over 1,000 vehicles record about 10,000 rows a second). The metrics count every cycle");
    cmd.add_option("--guard", o.guard,
                   "No-starving-valve guard (weight floor + revisit bound): on|off (default: the scenario's; off "
                   "reproduces the paper)")
        ->check(CLI::IsMember({"on", "off"}));
  }
  cmd.add_option("--seed", o.seed, "Seed of the mission: the start-pose jitter, the leaks --random-leaks draws and the sensors' noise; the same seed gives the same mission")
      ->check(MustBeWholeNumber);
  cmd.add_option("--random-leaks", o.random_leaks,
                 "Hide N random leaks from the server, drawn from the seed (onsets uniform in [0.1, 0.9] of the "
                 "mission), replacing the scenario's leaks: the vehicles' sensors can see them, the server is not told")
      ->check(MustBeIn(0, 1000, /*whole=*/true));
  cmd.add_option("--leak-sites", o.leak_sites,
                 "Where random leaks are: valves (by the risk of the profile flown: --profile, else the scenario's default), valves-even, seabed (open water "
                 "1 m from every valve), flowlines (along the scenario's flowlines, 1 m from every valve) or joints "
                 "(at the flowlines' vertices: tie-ins, flanges; the same clearances); default valves")
      ->check(CLI::IsMember({"valves", "valves-even", "seabed", "flowlines", "joints"}));
  if (mission) {
    cmd.add_option("--steer", o.steer,
                   "posterior: vehicles steer on the risk layer the sensors' scans update (the Bayesian loop, the "
                   "default where the scenario has sensors); prior: on the profile's weights alone, the scans only "
                   "scored (the paper's fixed profiles)")
        ->check(CLI::IsMember({"posterior", "prior"}));
  }
  cmd.add_option("--start-jitter", o.start_jitter_m,
                 "Radius (m) within which each vehicle starts around its start_m, drawn from the seed (default: the "
                 "scenario's, 0.2; 0 = exactly at start_m)");
  cmd.add_option("--forgetting", o.forgetting_time_s,
                 "Coverage forgetting time constant in seconds (default: the scenario's; inf = the paper's)");
  cmd.add_option("--basis-order,-K", o.basis_order, "Wave numbers per dimension K (default: the scenario's)");
  cmd.add_option("--turn-radius", o.min_turn_radius_m,
                 "Tightest turn of the SMC direction in metres: the vehicle loops back through a hot valve instead of "
                 "hovering on it (default: the scenario's; 0 = turn at once, the paper's law)");
  cmd.add_option("--final-approach", o.final_approach_m,
                 "Within this many metres of a valve its target wants, ahead and in sight, an ergodic vehicle flies "
                 "straight to it, so that a pass near it inspects it (default: the scenario's; generated fields 1.5; "
                 "0 = the paper's law)");
  cmd.add_option("--model", o.model,
                 "Motion model of every vehicle: bluerov2 (Box2D dynamics) or single_integrator (the paper's "
                 "constant-speed point); default: as in the scenario")
      ->check(CLI::IsMember({"bluerov2", "single_integrator"}));
  if (!mission) {
    cmd.footer("An agent host must run the server's scenario with the same --vehicles, --seed, --start-jitter, -K, "
               "--forgetting, --turn-radius, --final-approach, --model and --controller (sage launch sees to it).");
  }
}

// Where the process's DDS traffic goes: agent hosts and operators on other machines.
void AddNetwork(CLI::App& cmd, NetworkOverrides& n, const std::string& default_from) {
  cmd.add_option("--interface", n.interface_name,
                 "Network interface for DDS, by name or IPv4 address (default: " + default_from +
                     "; lo = this machine only)");
  cmd.add_option("--peer", n.peers,
                 "IPv4 address or host name of another machine of the mission (repeat for each); discovery without "
                 "multicast looks there (default: " + default_from + ")");
  cmd.add_option("--multicast", n.multicast, "DDS discovery by multicast on the interface: on|off (default: " +
                                                 default_from + ", off)")
      ->check(CLI::IsMember({"on", "off"}));
}

void AddController(CLI::App& cmd, std::string& controller) {
  cmd.add_option("--controller,-c", controller, "ergodic (SMC) or astar (the fixed inspection tour)")
      ->check(CLI::IsMember({"ergodic", "astar"}))
      ->capture_default_str();
}

// The live view's two servers, on 127.0.0.1 behind the mission's token (RUN_DIR/live_token).
void AddLiveView(CLI::App& cmd, std::string& http, std::string& foxglove) {
  cmd.add_option("--http", http,
                 "Port of the live view, a page on 127.0.0.1 that shows the fleet, the valves' risk and the events, and "
                 "takes an operator's requests with the mission's token (0: any free port, printed; off: none)")
      ->capture_default_str();
  cmd.add_option("--foxglove", foxglove,
                 "Port of the Foxglove WebSocket (foxglove.websocket.v1: vehicle poses, valves, the risk grid) on "
                 "127.0.0.1, for Foxglove or Lichtblick with the printed address (0: any free port; off: none)")
      ->capture_default_str();
}

void AddCyclePriority(CLI::App& cmd, int& priority) {
  cmd.add_option("--cycle-priority", priority,
                 "Real-time priority (SCHED_FIFO, 1..99) of the server's cycle, the fleet's critical path, so that the "
                 "vehicles' physics and a browser on the same machine do not hold it up; the threads it starts run at "
                 "normal priority. Needs root or CAP_SYS_NICE (without, it runs at normal priority, and says so when "
                 "a priority other than the default was asked for); 0: none")
      ->check(MustBeIn(0, 99, /*whole=*/true))
      ->capture_default_str();
}

// identity: whose certificate the command joins a secured mission with ("operator": commands
// that write; "viewer": sage status, which may write nothing).
void AddMissionDir(CLI::App& cmd, OperatorCommand& o, const std::string& identity = "operator") {
  cmd.add_option("--mission", o.mission_dir, "Run directory of the mission (default: $SAGE_MISSION or runs/latest)");
  AddNetwork(cmd, o.network, "the mission's, in mission.json");
  cmd.add_flag("--insecure", o.insecure,
               "Plain DDS instead of the mission's " + identity + " identity (mission.json security_dir); a secured " +
                   (identity == "operator" ? std::string("mission does not hear such a command")
                                           : std::string("mission is not heard that way")));
}

// One line for a mistyped or missing command word, at any depth: "unknown command 'frobnicate'
// of sage vehicle (commands: add, remove)", "sage risk needs a command (commands: set)"; any
// other error names the command it is about ("sage vehicle remove: id is required").
bool ReportUnknownCommand(const CLI::App& app, int argc, char** argv, std::string& path) {
  const CLI::App* level = &app;
  path = "sage";
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') break;
    const auto subs = level->get_subcommands([](const CLI::App*) { return true; });
    if (subs.empty()) break;
    const CLI::App* next = nullptr;
    std::string commands;
    for (const CLI::App* sub : subs) {
      if (sub->get_name() == word) next = sub;
      commands += (commands.empty() ? "" : ", ") + sub->get_name();
    }
    if (next == nullptr) {
      std::cerr << "sage: error: unknown command '" << word << "' of " << path << " (commands: " << commands << "; see "
                << path << " --help)\n";
      return true;
    }
    level = next;
    path += " " + word;
  }
  // A command word with commands of its own, given none.
  const auto subs = level->get_subcommands([](const CLI::App*) { return true; });
  if (subs.empty() || std::any_of(subs.begin(), subs.end(), [](const CLI::App* sub) { return sub->parsed(); })) {
    return false;
  }
  std::string commands;
  for (const CLI::App* sub : subs) commands += (commands.empty() ? "" : ", ") + sub->get_name();
  std::cerr << "sage: error: " << path << " needs a command (commands: " << commands << "; see " << path << " --help)\n";
  return true;
}

// Edit distance (insertions, deletions, substitutions), for "did you mean".
std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// The command the parse chose, as typed after "sage" ("run", "field generate"; "" for none).
std::string ParsedCommand(const CLI::App& app) {
  std::string path;
  for (const CLI::App* level = &app;;) {
    const auto chosen = level->get_subcommands();
    if (chosen.empty()) return path;
    level = chosen.front();
    path += (path.empty() ? "" : " ") + level->get_name();
  }
}

// An input error after the parse, as CLI11's are told: an option's value ("--duration = -1: ...")
// names its command and where its options are explained, so every bad option reads alike
// ("sage: error: run: --duration = -1: ... (see sage run --help)"); a file's or a field's error
// is said as it is.
std::string AsInputError(const CLI::App& app, const std::string& message) {
  const std::string command = ParsedCommand(app);
  if (command.empty() || !message.starts_with("--")) return message;
  return command + ": " + message + " (see sage " + command + " --help)";
}

// An option the command does not have, said as such with the nearest it does have ("The
// following arguments were not expected: 20 --durations" had named the value first and offered
// nothing). Words that read as numbers (-3, -0.5) are values, not options.
bool ReportUnknownOption(const CLI::App& app, int argc, char** argv) {
  const CLI::App* level = &app;
  std::string path = "sage";
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word.empty() || word[0] == '-') break;
    const CLI::App* next = nullptr;
    for (const CLI::App* sub : level->get_subcommands([](const CLI::App*) { return true; })) {
      if (sub->get_name() == word) next = sub;
    }
    if (next == nullptr) break;
    level = next;
    path += " " + word;
  }
  for (int i = 1; i < argc; ++i) {
    std::string word = argv[i];
    if (word.size() < 2 || word[0] != '-' || word == "--" || std::isdigit(static_cast<unsigned char>(word[1])) ||
        word[1] == '.') {
      continue;
    }
    if (const std::size_t eq = word.find('='); eq != std::string::npos) word.resize(eq);
    bool known = false;
    for (const CLI::App* a = level; a != nullptr && !known; a = a->get_parent()) known = a->get_option_no_throw(word) != nullptr;
    if (known) continue;
    std::string nearest;
    std::size_t best = std::max<std::size_t>(2, word.size() / 4) + 1;
    for (const CLI::Option* option : level->get_options()) {
      for (const std::string& name : option->get_lnames()) {
        const std::size_t d = EditDistance(word, "--" + name);
        if (d < best) best = d, nearest = "--" + name;
      }
    }
    // compare flies both controllers: a controller given is not wanted, rather than unknown.
    const bool controller = path == "sage compare" && (word == "-c" || word == "--controller");
    std::cerr << "sage: error: " << (path == "sage" ? "" : path.substr(5) + ": ") << word << ": no such option"
              << (controller ? "; compare flies both controllers, ergodic and then A* (sage run -c flies one)"
                  : nearest.empty() ? "" : "; did you mean " + nearest + "?")
              << " (see " << path << " --help)\n";
    return true;
  }
  return false;
}

// CLI11's words for an option given more often than it takes, in the project's ("--duration: At
// Most 1 required but received 2" had read as if a second value were wanted).
// The finite number `text` is, all of it; nullopt for anything else ("2.5x", "abc", "inf", "").
std::optional<double> NumberIn(const std::string& text) {
  // Decimal as typed, all of it (std::stod had taken "  2" and "0x10" as numbers); a leading '+'
  // allowed; -0 is 0 (it had been said back as "risk -0 ... now -0.0 %").
  const std::string_view digits = text.starts_with('+') ? std::string_view(text).substr(1) : std::string_view(text);
  double value = 0.0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value, std::chars_format::general);
  if (digits.empty() || (digits.front() == '-' && text.starts_with('+')) || error != std::errc() ||
      end != digits.data() + digits.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value == 0.0 ? 0.0 : value;
}

std::string InOurWords(const std::string& message) {
  // Plain string work, no std::regex: a refusal echoes what was typed, and libstdc++'s regex
  // recursed once a character (a 100,000-character value had crashed the command).
  // CLI11's "Could not convert: --duration = abc" said nothing of what was wanted.
  constexpr std::string_view kNotConverted = "Could not convert: ";
  if (message.starts_with(kNotConverted)) {
    // "--xts = 2.5" is a number, not a whole one; "--duration = abc" is none.
    const std::string said = message.substr(kNotConverted.size());
    const std::size_t eq = said.find(" = ");
    const std::string value = eq == std::string::npos ? "" : said.substr(eq + 3);
    return said + (NumberIn(value) ? ": must be a whole number" : ": must be a number");
  }
  const std::size_t colon = message.find(": ");
  if (colon == std::string::npos || message.find_first_of(" \t\n") < colon) return message;
  const std::string option = message.substr(0, colon), rest = message.substr(colon + 2);
  if (rest.starts_with("= ")) return option + " " + rest;  // Echoed's "OPTION: = VALUE: ..."
  // A check that names its option itself ("--vehicles: --vehicles = 0: ..." had said it twice).
  if (rest.starts_with(option + " = ")) return rest;
  // "--duration: 1 required FLOAT missing": the option given with no value after it.
  constexpr std::string_view kMissing = " missing";
  if (rest.ends_with(kMissing) && rest.find(" required ") != std::string::npos) {
    const std::size_t required = rest.find(" required ");
    const std::string type = rest.substr(required + 10, rest.size() - kMissing.size() - required - 10);
    const std::string what = type == "FLOAT" ? "a number" : type == "INT" || type == "UINT" ? "a whole number" : "a value";
    return option + ": needs " + what + " after it";
  }
  constexpr std::string_view kRepeated = "At Most 1 required but received ";
  if (rest.starts_with(kRepeated)) {
    const std::string count = rest.substr(kRepeated.size());
    if (!count.empty() && count.find_first_not_of("0123456789") == std::string::npos) {
      return option + ": given " + count + " times; give it once";
    }
  }
  return message;
}

}  // namespace

std::string RangeProblem(const std::string& text, double low, double high, bool whole) {
  const std::optional<double> value = NumberIn(text);
  if (value && *value >= low && *value <= high && (!whole || *value == std::floor(*value))) return "";
  return whole ? fmt::format("must be a whole number in {}..{}", low, high) : fmt::format("must be a number in [{}, {}]", low, high);
}

int RunCli(int argc, char** argv) {
  CLI::App app{
      "sage: ergodic inspection of subsea Christmas-tree valves (SAGE Fleet).\n"
      "Vehicles spend time at each valve in proportion to its live risk, using the spectral multiscale\n"
      "coverage law; the A* inspection tour is the baseline.",
      "sage"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "sage 0.2.0");

  RunCommand run_cmd;
  CLI::App* run = app.add_subcommand("run", "Run one mission in-process; print the per-valve table (the paper's Table 1 "
                                            "layout) and write DIR/metrics.json, trajectory.csv as it runs, and the charts (plot, metric, revisits: .svg and .png) at the end");
  AddScenarioOverrides(*run, run_cmd.scenario, OverrideSet::kMission, "scenarios/two_xt.yaml");
  AddController(*run, run_cmd.controller);
  run->add_option("--out,-o", run_cmd.out_dir, "Run directory (default: runs/<scenario>_<profile>_<controller>)")->check(MustBeAPathOrLeftOut);

  RunCommand compare_cmd;
  std::string calibrate = "on";
  CLI::App* compare = app.add_subcommand("compare", "Run A* and ergodic control on the same mission, side by side; "
                                                    "writes DIR/astar and DIR/ergodic");
  AddScenarioOverrides(*compare, compare_cmd.scenario, OverrideSet::kMission, "scenarios/two_xt.yaml");
  compare->add_option("--out,-o", compare_cmd.out_dir, "Output directory (default: runs/<scenario>_<profile>_compare)")->check(MustBeAPathOrLeftOut);
  compare->add_option("--calibrate-wait", calibrate,
                      "on: set A*'s wait per lap so it spends as long near the dominant valve as ergodic control (the "
                      "paper's protocol); off: use the scenario's astar.wait_per_lap_s")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();

  EvaluateCommand eval_cmd;
  CLI::App* evaluate = app.add_subcommand("evaluate", "Inspection metrics of a recorded trajectory (CSV with columns t, "
                                                      "vehicle, x, y), e.g. a real vehicle's log");
  evaluate->add_option("trajectory", eval_cmd.trajectory_path, "Trajectory CSV")->required();
  evaluate->add_option("--scenario,-s", eval_cmd.scenario_path, "Scenario YAML giving the valves and risk profiles")->required();
  evaluate->add_option("--profile,-p", eval_cmd.profile, "Risk profile (default: the scenario's default_profile)");
  evaluate->add_option("--duration", eval_cmd.duration_s, "Mission length in seconds (default: the last sample's time)");
  evaluate->add_option("--out,-o", eval_cmd.out_dir, "Also write metrics.json and the charts (plot, metric, revisits: .svg and .png) here")->check(MustBeAPath);

  LaunchCommand launch_cmd;
  CLI::App* launch = app.add_subcommand("launch", "Run a fleet mission over Cyclone DDS: the server and agent hosts as "
                                                  "processes on a private loopback-only domain; Ctrl-C stops cleanly");
  AddScenarioOverrides(*launch, launch_cmd.scenario, OverrideSet::kMission, "scenarios/fleet_field.yaml",
                       /*scenario_required=*/false);
  AddNetwork(*launch, launch_cmd.scenario.network, "the scenario's network");
  AddController(*launch, launch_cmd.controller);
  launch->add_option("--time-scale", launch_cmd.time_scale, "Mission seconds per wall second (1 = real time)")
      ->check(MustBeTimeScale)
      ->capture_default_str();
  launch->add_option("--out,-o", launch_cmd.out_dir, "Run directory (default: runs/<scenario>_launch)")->check(MustBeAPathOrLeftOut);
  launch->add_option("--hosts", launch_cmd.hosts, "Agent host processes for the fleet (default: one per 10,000 vehicles; on one machine more only multiply the DDS samples each host reads)")->check(MustBePositive);
  launch->add_option("--domain", launch_cmd.domain,
                     "DDS domain id 0..230 (secured, the default) or 0..232 (--insecure) (default: a free one, reserved "
                     "machine-wide)");
  launch->add_flag("--no-latest", launch_cmd.no_latest,
                   "Leave runs/latest alone (scripts and benchmarks that run many missions); operators then need "
                   "--mission DIR");
  CLI::Option* launch_security = launch->add_option(
      "--security", launch_cmd.security_dir,
      "DDS Security directory from sage security init whose identities the mission's processes use (default: new "
      "ones for this mission in RUN_DIR/security)");
  launch->add_flag("--insecure", launch_cmd.insecure,
                   "Plain DDS: no authentication, no encryption, any local process can join the mission (default: DDS "
                   "Security on)")
      ->excludes(launch_security);
  AddLiveView(*launch, launch_cmd.http, launch_cmd.foxglove);
  AddCyclePriority(*launch, launch_cmd.cycle_priority);
  launch->add_option("--resume", launch_cmd.resume_dir,
                     "Bring back the mission whose server died, from the checkpoint in this run directory (no "
                     "scenario or overrides: the run's own are used); vehicles still flying carry on, the others are "
                     "restarted where the record last saw them");

  ServerCommand server_cmd;
  CLI::App* server = app.add_subcommand("server", "The mission server alone (sage launch starts it for you)");
  AddScenarioOverrides(*server, server_cmd.scenario, OverrideSet::kMission, "scenarios/fleet_field.yaml");
  AddNetwork(*server, server_cmd.scenario.network, "the scenario's network");
  AddController(*server, server_cmd.controller);
  server->add_option("--time-scale", server_cmd.time_scale, "Mission seconds per wall second (1 = real time)")
      ->check(MustBeTimeScale)
      ->capture_default_str();
  server->add_option("--out,-o", server_cmd.out_dir, "Run directory (default: runs/<scenario>_server)")->check(MustBeAPathOrLeftOut);
  server->add_option("--domain", server_cmd.domain, "DDS domain id 0..232")->required();
  server->add_flag("--quiet", server_cmd.quiet, "No progress lines");
  server->add_flag("--launched", server_cmd.launched, "Started by sage launch (which writes mission.json)")->group("");
  server->add_option("--security", server_cmd.security_dir,
                     "DDS Security directory (sage security init): the server's identity there (default: plain DDS)");
  server->add_flag("--resume", server_cmd.resume,
                   "Continue the mission recorded in --out from its checkpoint (give the run's scenario.yaml)");
  server->add_option("--resumes", server_cmd.resumes, "How many times the mission was resumed before (for metrics.json)");
  server->add_option("--start-in", server_cmd.start_in_s,
                     "Wall seconds from now to the mission's first cycle (t = 0, or a resumed mission's next), so "
                     "that agent hosts started with the server are all in from it (sage launch gives 1 s + 1 ms per "
                     "vehicle)")
      ->check(MustBeIn(0.0, 600.0))
      ->capture_default_str();

  AddLiveView(*server, server_cmd.http, server_cmd.foxglove);
  AddCyclePriority(*server, server_cmd.cycle_priority);

  ViewCommand view_cmd;
  CLI::App* view = app.add_subcommand(
      "view", "Watch a finished or partial mission in the live view's page, from its run directory, with a time "
              "slider and play/pause; serves on 127.0.0.1 until Ctrl-C (the address, with its token, is printed)");
  view->add_option("run_dir", view_cmd.run_dir, "Run directory (trajectory.csv, fleet_events.csv, risk_events.csv, "
                                                "scenario.yaml, metrics.json)")
      ->required();
  view->add_option("--http", view_cmd.http, "Port of the page on 127.0.0.1 (0: any free port)")->capture_default_str();

  AgentsCommand agents_cmd;
  CLI::App* agents = app.add_subcommand("agents", "An agent host: several BlueROV2s in one Box2D world (sage launch "
                                                  "starts them)");
  AddScenarioOverrides(*agents, agents_cmd.scenario, OverrideSet::kVehicles, "scenarios/fleet_field.yaml");
  AddNetwork(*agents, agents_cmd.scenario.network, "the scenario's network");
  AddController(*agents, agents_cmd.controller);
  agents->add_option("--domain", agents_cmd.domain, "DDS domain id 0..232")->required();
  agents->add_option("--security", agents_cmd.security_dir,
                     "DDS Security directory (sage security init): the agent host's identity there (default: plain DDS)");
  agents->add_option("--offset", agents_cmd.offset, "First of the fleet's vehicles this host simulates")->capture_default_str();
  agents->add_option("--count", agents_cmd.count, "How many of them (default: all from --offset on)");
  agents->add_option("--join", agents_cmd.join, "Simulate the vehicle that joins in the scenario's fleet_events under this name");
  agents->add_option("--add", agents_cmd.add, "Simulate this many new vehicles with the ids the server issued (sage vehicle add)");
  agents->add_option("--first-id", agents_cmd.first_id, "Fleet id of the first vehicle (default: its index in the fleet)");
  agents->add_option("--resume", agents_cmd.resume_dir,
                     "Pick the --ids vehicles up where the crashed mission recorded in this run directory left them");
  agents->add_option("--ids", agents_cmd.ids, "With --resume: the fleet ids to simulate")->delimiter(',');
  agents->add_option("--start-at", agents_cmd.start_at_s,
                     "Mission time (s) of this host's first cycle at the earliest: a joining vehicle started ahead "
                     "joins at exactly that cycle, as in sage run (sage launch does this for fleet_events joins)")
      ->check(CLI::NonNegativeNumber);
  CLI::Option* lose_at = agents->add_option("--lose-at", agents_cmd.lose_at_s,
                                            "Mission time (s) at which the host SIGKILLs itself, at that exact cycle: "
                                            "the scenario's loss of its vehicles (sage launch does this)")
                             ->check(CLI::NonNegativeNumber);
  agents->add_option("--leave-at", agents_cmd.leave_at_s,
                     "Mission time (s) at which its vehicles leave cleanly, at that exact cycle")
      ->check(CLI::NonNegativeNumber)
      ->excludes(lose_at);

  OperatorCommand op;
  CLI::App* vehicle = app.add_subcommand("vehicle", "Add vehicles to, or remove one from, the running mission");
  vehicle->require_subcommand(1);
  CLI::App* vehicle_add = vehicle->add_subcommand("add", "Vehicles with ids the server issues join the running mission "
                                                         "(a new agent host process)");
  // `sage vehicle add 2` as well as `-c 2`: a new user's first try had been refused ("The following
  // argument was not expected: 2").
  vehicle_add->add_option("count,--count,-c", op.add_count, "How many vehicles (1..10000)")->capture_default_str();
  AddMissionDir(*vehicle_add, op);
  CLI::App* vehicle_remove = vehicle->add_subcommand("remove", "Take a vehicle out of the running mission cleanly");
  vehicle_remove->add_option("vehicle", op.remove_vehicle,
                             "The vehicle: its name (rov2), as every log names it, or its id (the launch's vehicles "
                             "are 0..N-1 in scenario order, rov1 is 0; joins and added ones follow)")
      ->required();
  AddMissionDir(*vehicle_remove, op);

  CLI::App* risk = app.add_subcommand("risk", "Change a valve's risk in the running mission");
  risk->require_subcommand(1);
  CLI::App* risk_set = risk->add_subcommand("set", "Set a valve's raw risk weight; vehicles re-allocate on the next cycle");
  risk_set->add_option("valve", op.valve, "Valve name, e.g. P1")->required();
  // Checked as typed: CLI11 had read an empty weight (an unset shell variable) as 0, taking the
  // valve out of the field.
  risk_set->add_option("weight", op.weight, "Raw weight in [0, 1e12] (weights are normalised over all valves)")
      ->required()
      ->check(MustBeIn(0.0, 1e12));
  risk_set->add_option("--source", op.source, "Who says so (logged by the server; 1 to 64 characters)")
      ->capture_default_str()
      ->check(MustBeASourceName);
  AddMissionDir(*risk_set, op);

  CLI::App* stop = app.add_subcommand("stop", "End the running mission now; its server writes the run directory");
  AddMissionDir(*stop, op);
  CLI::App* status = app.add_subcommand(
      "status", "Where the running mission stands: its time, the server's cycle, vehicles flying and lost, and each "
                "vehicle heard with its position and speed (read only: joins as the mission's viewer)");
  status->add_option("--listen", op.status_listen_s,
                     "Seconds to hear the vehicles' states once the mission has answered, and up to 3 s more while "
                     "fewer are heard than fly (0.2..60; each vehicle sends one a control cycle)")
      ->capture_default_str()
      ->check(MustBeIn(0.2, 60.0));
  status->add_flag("--all", op.status_all, "List every vehicle heard (default: the first 40 by id, and a count of the rest)");
  AddMissionDir(*status, op, "viewer");

  SecurityInitCommand security_cmd;
  CLI::App* security = app.add_subcommand("security", "DDS Security material for missions");
  security->require_subcommand(1);
  CLI::App* security_init = security->add_subcommand(
      "init", "Write a CA, identities for the roles server, agent_host, operator and viewer, and governance and "
              "permissions (which role may publish and read each mission topic; everything encrypted) signed by the "
              "CA, into a new directory (mode 0700, keys 0600); sage launch --security DIR uses it");
  security_init->add_option("dir", security_cmd.dir, "Directory to create (must not exist, or be empty)")->required();
  security_init->add_option("--validity-days", security_cmd.validity_days,
                            "Days the certificates and permissions are valid, from an hour ago (1..3650)")
      ->check(MustBeIn(1, 3650, /*whole=*/true))
      ->capture_default_str();

  maps::FieldOptions field_options;
  std::string field_out;
  CLI::App* field = app.add_subcommand("field", "Synthetic subsea fields: of any size for scale runs, and the example seabed");
  field->require_subcommand(1);
  CLI::App* generate = field->add_subcommand(
      "generate", "Write a realistic scenario of any size: XTs in manifold clusters, valves at the inspection "
                  "standoff, graded risk (a few valves suspected of leaking, weighted 10-20), a fleet of BlueROV2s, "
                  "settings sized for the field (over 1,000 vehicles a trajectory.csv of about 10,000 rows a mission "
                  "second: trajectory_rate_hz), and leak sensors if asked; the same seed gives the same field (the "
                  "field grows with the counts: about 80 m^2 of seabed per XT)");
  // The three counts size each other (WithCountsSizedToEachOther): no fixed default shown, which a
  // new user had read as the count given with another ("--valves 2" gives 1 XT, not 28).
  CLI::Option* generate_xts = generate->add_option(
      "--xts", field_options.xts,
      "Christmas trees (1..50000); without it, as many as --valves needs at about 3.1 valves an XT, or 28 with "
      "neither");
  CLI::Option* generate_valves = generate->add_option(
      "--valves", field_options.valves, "Valves in all, 2 to 5 per XT; without it, about 3.1 per XT (87 for 28)");
  CLI::Option* generate_vehicles = generate->add_option(
      "--vehicles", field_options.vehicles,
      "BlueROV2s (1..50000); without it, 24 for every 28 XTs (24 with no count given); given alone, the field keeps "
      "28 XTs and 87 valves (use --xts to grow it)");
  generate->add_option("--seed", field_options.seed, "Same seed, same field; also the mission's seed")
      ->check(MustBeWholeNumber)
      ->capture_default_str();
  generate->add_option("--area-per-xt", field_options.area_per_xt_m2, "Seabed per XT (m^2), 50..10000")
      ->capture_default_str();
  generate->add_option("--name", field_options.name,
                       "The scenario's name (default: field_<xts>xt_<valves>v_<vehicles>rov_s<seed>, then _camera or "
                       "_camera_sonar with --sensors)");
  std::string field_sensors = "none";
  generate
      ->add_option("--sensors", field_sensors,
                   "Leak sensors on every vehicle: none; camera (two_xt_leaks' 1.2 m camera, the vehicles turning to "
                   "the valves in reach); camera+sonar (fleet_field_leaks' camera and 4 m sonar). With sensors the "
                   "field can hide leaks (sage run --random-leaks, sage bench leaks) and the vehicles steer on what "
                   "they see")
      ->capture_default_str();
  generate->add_option("--out,-o", field_out, "Scenario file to write")->required()->check(MustBeAPath);
  std::uint64_t seabed_seed = 7;
  std::string seabed_name, seabed_out;
  CLI::App* seabed = field->add_subcommand(
      "seabed", "Write the example seabed field: a manifold, four XTs, their jumpers, an export line and an "
                "umbilical on a slope with sand waves, a rock ridge, a scarp, a pockmark and boulders, flown by three "
                "BlueROV2s 0.8-2.0 m above the local seabed; the bathymetry (gridded XYZ depths) is written beside "
                "the scenario as NAME.xyz (another scenario's map is not written over). The same seed gives the same files "
                "(scenarios/manifold_slope.yaml is seed 7)");
  seabed->add_option("--seed", seabed_seed, "Moves the boulders, the sand waves and the risk; also the mission's seed")
      ->check(MustBeWholeNumber)
      ->capture_default_str();
  seabed->add_option("--name", seabed_name,
                     "The scenario's name and its map's file name (NAME.xyz; default: the --out file's name, "
                     "manifold_slope for -o manifold_slope.yaml)");
  seabed->add_option("--out,-o", seabed_out, "Scenario file to write (the map goes in the same folder)")->required()->check(MustBeAPath);

  BenchScaleCommand bench_cmd;
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks of the whole system");
  bench->require_subcommand(1);
  CLI::App* bench_scale = bench->add_subcommand(
      "scale", "How the fleet scales: for each fleet size N a field that grows with it (N XTs, 3.5 N valves, N "
               "BlueROV2s; written to DIR/fields), flown by the ergodic fleet and by the A* tours, in-process and over "
               "DDS (sage launch); writes DIR/scale.md, scale.json and scale.svg and prints the table. Runs one "
               "mission at a time (real time over DDS: about 2 x duration per N), progress on stderr");
  bench_scale
      ->add_option("--vehicles", bench_cmd.vehicles,
                   "Fleet sizes, comma-separated, each 1..10000 (e.g. 1,10,100,1000,10000)")
      ->check([](const std::string& text) {
        try {
          ParseVehicleCounts(text);
          return std::string();
        } catch (const maps::ScenarioError& e) {
          return std::string(e.what());
        }
      })
      ->capture_default_str();
  bench_scale
      ->add_option("--transport", bench_cmd.transport,
                   "inproc (the mission in one process, as fast as it runs), dds (sage launch: server and agent hosts "
                   "as processes on Cyclone DDS, at real time) or both")
      ->check(CLI::IsMember({"inproc", "dds", "both"}))
      ->capture_default_str();
  bench_scale->add_option("--out,-o", bench_cmd.out_dir, "Output directory")->capture_default_str()->check(MustBeAPathOrLeftOut);
  bench_scale->add_option("--duration", bench_cmd.duration_s, "Mission seconds of each run (up to a week)")
      ->check(MustBeADuration)
      ->capture_default_str();
  bench_scale->add_option("--seed", bench_cmd.seed, "Seed of the fields and the missions")
      ->check(MustBeWholeNumber)
      ->capture_default_str();
  bench_scale
      ->add_option("--repeat", bench_cmd.repeat,
                   "Runs of each configuration, 1..10, made round by round (every configuration once, then again), so "
                   "that a shared machine's slow spells fall on all of them: the table shows each one's median run, "
                   "scale.json every run, and scale.md lists them all")
      ->check(MustBeIn(1, 10, /*whole=*/true))
      ->capture_default_str();

  BenchLeaksCommand leaks_cmd;
  CLI::App* bench_leaks = bench->add_subcommand(
      "leaks", "How long a leak the server is not told of goes unnoticed: a Monte Carlo over seeds, each run hiding "
               "random leaks (drawn from its seed) from the server and flying the same mission under each "
               "configuration (the ergodic fleet on the Bayesian risk loop, the A* tours, the ergodic fleet on each "
               "fixed profile); the time from onset to first detection and to confirmation, revisits after it and "
               "false alarms. Writes DIR/leaks.md, leaks.json and leaks.svg (the distribution of detection times) and "
               "prints the table; progress on stderr. The scenario's vehicles need sensors (see "
               "scenarios/two_xt_leaks.yaml)");
  bench_leaks->add_option("scenario", leaks_cmd.scenario.scenario_path, "Scenario YAML with sensors")->required();
  bench_leaks->add_option("--runs", leaks_cmd.runs, "Monte Carlo runs (seeds --seed, --seed + 1, ...)")->capture_default_str();
  bench_leaks->add_option("--leaks", leaks_cmd.leaks, "Hidden leaks per run (onsets uniform in [0.1, 0.9] of the mission)")
      ->capture_default_str();
  bench_leaks
      ->add_option("--sites,--leak-sites", leaks_cmd.sites,
                   "Where the leaks are: valves (by the risk of the profile flown: --profile, else the scenario's default), valves-even, seabed (open water 1 m "
                   "from every valve), flowlines (along the scenario's flowlines, 1 m from every valve) or joints (at "
                   "the flowlines' vertices, the same clearances)")
      ->check(CLI::IsMember({"valves", "valves-even", "seabed", "flowlines", "joints"}))
      ->capture_default_str();
  bench_leaks->add_option("--seed", leaks_cmd.first_seed, "Seed of the first run")->check(MustBeWholeNumber)->capture_default_str();
  bench_leaks
      ->add_option("--configs", leaks_cmd.configs,
                   "What flies each run, comma-separated: bayes (ergodic on the Bayesian loop), looks (A* legs to the valves "
                   "the look planner picks on the scans: astar.order looks), astar (the shortest tours), fixed (ergodic on "
                   "each of the scenario's profiles, the loop not steering)")
      ->capture_default_str();
  bench_leaks->add_option("--profile,-p", leaks_cmd.scenario.profile,
                          "Profile of bayes, looks and astar (default: the scenario's default_profile)");
  bench_leaks->add_option("--duration", leaks_cmd.scenario.duration_s, "Mission length in seconds (default: the scenario's)");
  bench_leaks->add_option("--vehicles,-n", leaks_cmd.scenario.vehicles, "Fleet size (default: the scenario's)");
  bench_leaks->add_option("--assignment", leaks_cmd.scenario.assignment, "Fleet coverage of the ergodic runs")
      ->check(CLI::IsMember({"shared", "partition", "regions"}));
  bench_leaks->add_option("--jobs,-j", leaks_cmd.jobs, "Missions flown at once (each on one thread)")->capture_default_str();
  bench_leaks->add_option("--out,-o", leaks_cmd.out_dir, "Output directory (default: runs/bench_leaks_<scenario>)")->check(MustBeAPathOrLeftOut);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Bad arguments: one line, like every other input error.
    std::string path;
    if (ReportUnknownCommand(app, argc, argv, path)) return 2;
    // An option the command does not have is said first, whatever CLI11 stopped at (`sage run
    // --helpp` had said only that the scenario was required).
    if (ReportUnknownOption(app, argc, argv)) return 2;
    std::string words = InOurWords(e.what());
    // `sage vehicle add 2 --count 3`: the argument and --count are one option to CLI11.
    if (constexpr std::string_view kCount = "--count: given "; path == "sage vehicle add" && words.starts_with(kCount)) {
      const std::string times = words.substr(kCount.size(), words.find(';') - kCount.size());  // "2 times"
      words = "the count was given " + times + " (the argument, --count and -c are one option); give it once";
    }
    std::cerr << "sage: error: " << (path == "sage" ? "" : path.substr(5) + ": ") << words << " (see " << path
              << " --help)\n";
    return 2;
  }

  spdlog::set_pattern("%^[%l]%$ %v");
  try {
    for (const int domain : {server_cmd.domain, agents_cmd.domain, launch_cmd.domain.value_or(0)}) {
      if (domain < 0 || domain > proto::kMaxDomainId) {
        // A launch is secured unless --insecure; a server or host only with --security.
        throw maps::ScenarioError(fmt::format("--domain = {}: must be in 0..{} (0..{} for a secured mission{})", domain,
                                              proto::kMaxDomainId, proto::kMaxSecureDomainId,
                                              *launch ? ", the default" : ": --security"));
      }
    }
    if (*run || *compare) {
      // Ctrl-C (or SIGTERM, SIGHUP) ends the mission where it is, with its whole record written.
      RunCommand& command = *run ? run_cmd : compare_cmd;
      if (*compare) compare_cmd.calibrate_wait = calibrate == "on";
      command.stop = StopOnSignals();
      const int status = *run ? CmdRun(command) : CmdCompare(command);
      return status == 130 && StopSignal() != 0 ? 128 + StopSignal() : status;
    }
    if (*evaluate) return CmdEvaluate(eval_cmd);
    if (*launch) {
      if (launch_cmd.resume_dir.empty() && launch_cmd.scenario.scenario_path.empty()) {
        throw maps::ScenarioError("scenario: give a scenario YAML (e.g. scenarios/fleet_field.yaml), or --resume RUN_DIR");
      }
      if (!launch_cmd.resume_dir.empty() && !launch_cmd.scenario.scenario_path.empty()) {
        throw maps::ScenarioError("--resume: resumes the run's own scenario; give no scenario file with it");
      }
      if (!launch_cmd.resume_dir.empty()) {
        // A resumed mission flies on with the controller and time scale its mission.json keeps
        // (its hosts that carried on run them already): one given here had been ignored in silence.
        std::string given = FirstScenarioOverride(launch_cmd.scenario);
        if (given.empty() && launch->count("--controller") > 0) given = "--controller";
        if (given.empty() && launch->count("--time-scale") > 0) given = "--time-scale";
        if (!given.empty()) {
          throw maps::ScenarioError("--resume: resumes the run's own scenario with its own options (its controller and "
                                    "time scale as in its mission.json); give no " + given + " with it");
        }
      }
      // A resumed mission shows what it showed: a live view or Foxglove socket the mission had off
      // stays off unless given again (both had come back on, on free ports).
      if (!launch_cmd.resume_dir.empty()) {
        if (const std::optional<LiveEndpoints> before = ReadLiveEndpoints(launch_cmd.resume_dir)) {
          if (launch->count("--http") == 0 && before->http_port < 0) launch_cmd.http = "off";
          if (launch->count("--foxglove") == 0 && before->foxglove_port < 0) launch_cmd.foxglove = "off";
        }
      }
      if (!launch_cmd.resume_dir.empty() && (launch_cmd.insecure || !launch_cmd.security_dir.empty())) {
        throw maps::ScenarioError("--resume: the mission keeps its own security (mission.json security_dir); give no "
                                  "--security or --insecure with it");
      }
      launch_cmd.stop = StopOnSignals();
      const int status = Launch(launch_cmd);
      // Stopped by a signal: the shell's convention, 128 + its number (130 for Ctrl-C).
      return status == 130 && StopSignal() != 0 ? 128 + StopSignal() : status;
    }
    if (*server) return CmdServer(server_cmd);
    if (*agents) return CmdAgents(agents_cmd);
    if (*view) return CmdView(view_cmd);
    // The mission as mission.json says, on this machine's network as the options say.
    const auto mission = [&] {
      MissionFile m = FindMission(op.mission_dir);
      // Found through runs/latest and not running: a mission that does run there is named (a later
      // launch that ended first leaves runs/latest on its own record).
      const auto running_elsewhere = [&] {
        if (!op.mission_dir.empty() || std::getenv("SAGE_MISSION") != nullptr) return std::string();
        const std::vector<std::string> running = RunningMissions();
        if (running.empty()) return std::string();
        return fmt::format("; {} running in {}: give --mission {}",
                           running.size() == 1 ? "a mission is" : fmt::format("{} missions are", running.size()),
                           fmt::join(running, ", "), running.front());
      };
      // A mission whose record is complete has ended: said at once, naming it (a command had
      // waited 3-6 s for an answer and said only that no mission listened on its domain).
      if (const RecordSummary record = ReadRecordSummary(m.run_dir); record.complete) {
        const std::string elsewhere = running_elsewhere();
        throw std::runtime_error(fmt::format("the mission in {} has ended (its record is complete, to t = {:.1f} s){}",
                                             m.run_dir, record.recorded_until_s,
                                             elsewhere.empty() ? ": none to take this; start one with sage launch"
                                                               : elsewhere));
      } else if (record.exists && m.launcher_pid > 0 && !IsRunningLauncher(m.launcher_pid)) {
        // Launched, unfinished, and its launcher gone: its server died (a command had waited 3 s
        // and said only "no mission is listening on DDS domain 153"). A server started by hand
        // names no launcher and is asked as before.
        throw std::runtime_error(fmt::format(
            "the mission in {} is not running: its server is gone and no sage launch runs it (its record stops at t = "
            "{:.1f} s{}); resume it with sage launch --resume {}{}",
            m.run_dir, record.recorded_until_s,
            record.has_checkpoint ? fmt::format(", checkpoint at t = {:.1f} s", record.checkpoint_s) : std::string(),
            m.run_dir, running_elsewhere()));
      }
      m.network = op.network.Applied(m.network);
      return m;
    };
    if (*vehicle_add) return AddVehicles(mission(), op.add_count, op.insecure);
    if (*vehicle_remove) return RemoveVehicle(mission(), op.remove_vehicle, op.insecure);
    if (*risk_set) return SetRisk(mission(), op.valve, op.weight, op.source, op.insecure);
    if (*stop) return StopMission(mission(), op.insecure);
    if (*status) {
      // Status only reads: an ended mission is told, not refused.
      const MissionFile m = FindMission(op.mission_dir);
      if (const RecordSummary record = ReadRecordSummary(m.run_dir); record.complete) return ShowEndedMission(m.run_dir, record);
      return ShowStatus(mission(), op.status_listen_s, op.status_all, op.insecure);
    }
    if (*security_init) return CmdSecurityInit(security_cmd);
    // Their log lines on stderr, as run's and launch's: stdout holds only what they report (a
    // field's [info] line had gone to stdout, so `2>/dev/null` did not quiet it).
    if (*generate || *seabed || *bench_scale || *bench_leaks) LogToStderr();
    if (*generate) {
      field_options.sensors = maps::ParseFieldSensors(field_sensors, "--sensors");
      return CmdFieldGenerate(WithCountsSizedToEachOther(field_options, generate_xts->count() > 0, generate_valves->count() > 0,
                                                         generate_vehicles->count() > 0),
                              field_out);
    }
    if (*seabed) return CmdFieldSeabed(seabed_seed, seabed_name, seabed_out);
    if (*bench_scale) return CmdBenchScale(bench_cmd);
    if (*bench_leaks) return CmdBenchLeaks(leaks_cmd);
  } catch (const maps::ScenarioError& e) {
    std::cerr << "sage: error: " << AsInputError(app, e.what()) << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {  // e.g. a DDS domain out of range
    std::cerr << "sage: error: " << AsInputError(app, e.what()) << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "sage: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace sage::server
