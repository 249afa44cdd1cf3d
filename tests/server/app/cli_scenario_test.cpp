#include "server/app/cli_scenario.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "maps/scenario/field_generator.h"
#include "server/app/cli.h"
#include "server/app/fleet_commands.h"
#include "server/app/operators.h"
#include "server/app/options.h"
#include "server/app/run_commands.h"
#include "server/report/mission_file.h"
#include "tests/server/app/run_sage.h"

namespace sage::server {
namespace {

using cli_test::RunSage;
using cli_test::SageRun;

const std::string kFleetField = std::string(SAGE_SOURCE_DIR) + "/scenarios/fleet_field.yaml";

ScenarioOverrides FleetField() {
  ScenarioOverrides o;
  o.scenario_path = kFleetField;
  return o;
}

// Without overrides the file is taken as it is.
TEST(ScenarioOverrides, NoneLeaveTheFileAlone) {
  const maps::Scenario file = maps::LoadScenario(kFleetField);
  const maps::Scenario loaded = LoadWithOverrides(FleetField());
  EXPECT_EQ(maps::EmitScenario(loaded), maps::EmitScenario(file));
}

// Every override lands in its field; a shorter mission drops the events after its end, and
// --model reaches the vehicle that joins later too (an agent host simulates it from the file).
TEST(ScenarioOverrides, EachLandsInItsField) {
  ScenarioOverrides o = FleetField();
  o.vehicles = 6;
  o.duration_s = 300.0;
  o.seed = 42;
  o.guard = "off";
  o.forgetting_time_s = 30.0;
  o.basis_order = 24;
  o.min_turn_radius_m = 0.4;
  o.final_approach_m = 1.2;
  o.model = "single_integrator";
  o.assignment = "partition";
  o.age_weighting_laps = 2.5;
  o.risk_share = 0.0;
  const maps::Scenario s = LoadWithOverrides(o);
  EXPECT_EQ(s.vehicles.size(), 6u);
  EXPECT_EQ(s.duration_s, 300.0);
  EXPECT_EQ(s.seed, 42u);
  EXPECT_FALSE(s.guard.enabled);
  EXPECT_EQ(s.ergodic.forgetting_time_s, 30.0);
  EXPECT_EQ(s.ergodic.basis_order, 24);
  EXPECT_EQ(s.ergodic.min_turn_radius_m, 0.4);
  EXPECT_EQ(s.ergodic.final_approach_m, 1.2);
  EXPECT_EQ(s.fleet.assignment, maps::FleetAssignment::kPartition);
  EXPECT_EQ(s.fleet.age_weighting_laps, 2.5);
  EXPECT_EQ(s.fleet.risk_share, 0.0);
  for (const maps::VehicleSpec& v : s.vehicles) EXPECT_EQ(v.model, maps::MotionModel::kSingleIntegrator) << v.name;
  ASSERT_EQ(s.fleet_events.size(), 1u);  // the join at 200 s stays, the loss at 400 s is past the end
  EXPECT_EQ(s.fleet_events[0].kind, maps::FleetEvent::Kind::kJoin);
  EXPECT_EQ(s.fleet_events[0].vehicle.model, maps::MotionModel::kSingleIntegrator);
}

// A bad value is one error naming the option, the value and what is allowed.
TEST(ScenarioOverrides, BadValuesNameTheOption) {
  struct Case {
    void (*set)(ScenarioOverrides&);
    std::string expected;
  };
  const Case cases[] = {
      {[](ScenarioOverrides& o) { o.vehicles = 0; }, "--vehicles = 0: must be >= 1"},
      {[](ScenarioOverrides& o) { o.duration_s = -5.0; }, "--duration = -5: must be > 0 and <= 604800 s"},
      // The option's name, not the file's (it had read "fleet_field.yaml: duration_s = 1e+09").
      {[](ScenarioOverrides& o) { o.duration_s = 1e9; }, "--duration = 1000000000: must be > 0 and <= 604800 s"},
      // Leaks no vehicle could see: refused as sage bench leaks refuses them.
      {[](ScenarioOverrides& o) { o.random_leaks = 2; }, "--random-leaks = 2: " + kFleetField + " has no sensors"},
      // The option, not the file (it had read "fleet_field.yaml: astar.order = looks", a key the file has not).
      {[](ScenarioOverrides& o) { o.order = "looks"; }, "--order = looks: the look planner chooses the next valves on the "
                                                         "vehicles' scans, and " + kFleetField + " has no sensors"},
      {[](ScenarioOverrides& o) { o.basis_order = 65; }, "--basis-order = 65: must be in 1..64"},
      {[](ScenarioOverrides& o) { o.forgetting_time_s = 0.0; }, "--forgetting = 0: must be > 0"},
      {[](ScenarioOverrides& o) { o.min_turn_radius_m = -0.1; }, "--turn-radius = -0.1: must be a finite number >= 0"},
      {[](ScenarioOverrides& o) { o.final_approach_m = 7.5; }, "--final-approach = 7.5: must be in [0, 5] m"},
      {[](ScenarioOverrides& o) { o.age_weighting_laps = std::nan(""); }, "--age-weighting = nan: must be in [0, 100]"},
      {[](ScenarioOverrides& o) { o.risk_share = 11.0; }, "--risk-share = 11: must be in [0, 10]"},
      // Checked on load, so `sage launch -p nope` fails before it starts any process.
      {[](ScenarioOverrides& o) { o.profile = "nope"; }, "fleet_field.yaml: profile = nope: must be one of routine"},
  };
  for (const Case& c : cases) {
    ScenarioOverrides o = FleetField();
    c.set(o);
    try {
      LoadWithOverrides(o);
      ADD_FAILURE() << "accepted: " << c.expected;
    } catch (const maps::ScenarioError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos) << e.what();
    }
  }
}

// A shorter mission leaves out the leaks and events after its end, and says so: the run's table
// had read "none hidden" for a leak --duration cut, without a word.
TEST(ScenarioOverrides, AShorterMissionSaysWhatItLeavesOut) {
  maps::Scenario file = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml");
  ASSERT_EQ(file.leaks.size(), 1u);  // at P3 from 120 s; leak_injection's event at 150 s
  // Flying one_extreme (the default, no events), another profile's event is not the mission's.
  EXPECT_EQ(LeftOutByDuration(file, 60.0, false),
            "--duration = 60: the mission ends before the leak at P3 from 120 s (left out)");
  EXPECT_EQ(LeftOutByDuration(file, 130.0, false), "");
  file.default_profile = "leak_injection";  // as --profile leak_injection leaves it
  EXPECT_EQ(LeftOutByDuration(file, 60.0, false),
            "--duration = 60: the mission ends before the leak at P3 from 120 s, 1 risk event(s) "
            "of profile leak_injection (left out)");
  EXPECT_EQ(LeftOutByDuration(file, 130.0, false),
            "--duration = 130: the mission ends before 1 risk event(s) of profile leak_injection (left out)");
  EXPECT_EQ(LeftOutByDuration(file, 60.0, true),  // --random-leaks draws the shorter mission's own
            "--duration = 60: the mission ends before 1 risk event(s) of profile leak_injection (left out)");
  EXPECT_EQ(LeftOutByDuration(file, 200.0, false), "");
  // A leak that starts as the shorter mission ends could only be missed: left out too.
  EXPECT_EQ(LeftOutByDuration(file, 120.0, false),
            "--duration = 120: the mission ends before the leak at P3 from 120 s, 1 risk event(s) "
            "of profile leak_injection (left out)");
  EXPECT_TRUE(maps::WithDuration(file, 120.0).leaks.empty());
  // fleet_field: a join at 200 s and a loss at 400 s.
  EXPECT_EQ(LeftOutByDuration(maps::LoadScenario(kFleetField), 300.0, false),
            "--duration = 300: the mission ends before 1 fleet event(s) (left out)");
  ScenarioOverrides o;
  o.scenario_path = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt_leaks.yaml";
  o.duration_s = 60.0;
  EXPECT_TRUE(LoadWithOverrides(o).leaks.empty());
}

// Regions or tours on a field of 1,000 valves or more want a vehicle per 100 valves: refused
// before anything runs (ten vehicles on the 35,000-valve field had planned for hours); the shared
// basis plans nothing and is let through, and so is a fleet of the size the refusal names.
TEST(CheckFleetFitsField, RefusesRegionsAndToursForAFleetFarSmallerThanItsField) {
  maps::FieldOptions options;
  options.xts = 300;
  options.valves = 1050;
  options.vehicles = 10;
  options.seed = 3;
  maps::Scenario s = maps::GenerateField(options);
  ASSERT_EQ(s.ValveCount(), 1050);
  s.fleet.assignment = maps::FleetAssignment::kRegions;
  try {
    CheckFleetFitsField(s, false);
    ADD_FAILURE() << "10 vehicles on 1,050 valves accepted";
  } catch (const maps::ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("fly at least 11 (-n 11)"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CheckFleetFitsField(s, true), maps::ScenarioError);  // the tours alike
  s.fleet.assignment = maps::FleetAssignment::kShared;
  EXPECT_NO_THROW(CheckFleetFitsField(s, false));
  EXPECT_THROW(CheckFleetFitsField(s, true), maps::ScenarioError);
  s.vehicles.push_back(s.vehicles.back());
  s.vehicles.back().name += "b";
  s.fleet.assignment = maps::FleetAssignment::kRegions;
  EXPECT_NO_THROW(CheckFleetFitsField(s, true));
  EXPECT_NO_THROW(CheckFleetFitsField(maps::LoadScenario(kFleetField), true));  // 20 valves: planned at once
}


// `sage launch --resume` flies the run's own scenario: an override given with it is named and
// refused (a resumed --duration 100 had run to the run's 60 s with exit 0); the network options
// are this machine's and pass.
TEST(ScenarioOverrides, ResumeNamesTheFirstOverrideGiven) {
  ScenarioOverrides o;
  EXPECT_EQ(FirstScenarioOverride(o), "");
  o.network.interface_name = "lo";
  o.network.peers = {"127.0.0.1"};
  EXPECT_EQ(FirstScenarioOverride(o), "");
  o.duration_s = 100.0;
  EXPECT_EQ(FirstScenarioOverride(o), "--duration");
  ScenarioOverrides p;
  p.steer = "prior";
  EXPECT_EQ(FirstScenarioOverride(p), "--steer");
  p.profile = "graded";
  EXPECT_EQ(FirstScenarioOverride(p), "--profile");
}

// Where a mission's directory is asked for, a wrong path says what it is, not
// "PATH/mission.json: cannot read" with a hint at an option the command may not have.
TEST(MissionFileDoor, SaysWhatTheGivenPathIs) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sage_mission_file_door";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto message = [](const std::string& path) {
    try {
      ReadMissionFile(path);
    } catch (const maps::ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message((dir / "nothing").string()), (dir / "nothing").string() + ": no such directory (a run directory of sage launch: start one with sage launch)");
  std::ofstream((dir / "file.txt").string()) << "x";
  EXPECT_NE(message((dir / "file.txt").string()).find("file.txt: a file, not a run directory"), std::string::npos);
  EXPECT_NE(message(dir.string()).find(": no mission.json: not the run directory of a sage launch"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// A port option offers "off" only where it is allowed (sage view is nothing but its page).
TEST(PortOption, OffersOffOnlyWhereAllowed) {
  EXPECT_EQ(PortOption("--http", "off"), std::nullopt);
  EXPECT_EQ(PortOption("--http", "8080"), 8080);
  const auto message = [](const std::string& text, bool off_allowed) {
    try {
      PortOption("--http", text, off_allowed);
    } catch (const maps::ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message("abc", true), "--http = abc: must be a port in 0..65535 (0: any free one) or off");
  EXPECT_EQ(message("abc", false), "--http = abc: must be a port in 0..65535 (0: any free one)");
  EXPECT_EQ(message("off", false), "--http = off: must be a port in 0..65535 (0: any free one)");
  EXPECT_EQ(message("65536", true), "--http = 65536: must be a port in 0..65535 (0: any free one) or off");
}


// A number option out of its range is told in the project's words (CLI11 had said "Value 5 not
// in range 0.000000 to 4.000000"), and the command refuses it with status 2.
TEST(RangeProblem, SaysWhatIsAllowed) {
  EXPECT_EQ(RangeProblem("0.5", 0.0, 4.0, false), "");
  EXPECT_EQ(RangeProblem("4", 0.0, 4.0, false), "");
  EXPECT_EQ(RangeProblem("5", 0.0, 4.0, false), "must be a number in [0, 4]");
  EXPECT_EQ(RangeProblem("-0.1", 0.0, 4.0, false), "must be a number in [0, 4]");
  EXPECT_EQ(RangeProblem("nan", 0.0, 4.0, false), "must be a number in [0, 4]");
  EXPECT_EQ(RangeProblem("2x", 0.0, 4.0, false), "must be a number in [0, 4]");
  EXPECT_EQ(RangeProblem("", 0.0, 4.0, false), "must be a number in [0, 4]");
  EXPECT_EQ(RangeProblem("1000", 0, 1000, true), "");
  EXPECT_EQ(RangeProblem("1001", 0, 1000, true), "must be a whole number in 0..1000");
  EXPECT_EQ(RangeProblem("2.5", 0, 1000, true), "must be a whole number in 0..1000");
  const std::string file = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
  // Refused with what was typed, as the scenario's refusals are ("--weight-exponent: must be ..." had
  // not said the value).
  // bench scale's duration at the door, before any field is generated (1e9 had failed each run
  // after making the fields, and written a table of dashes); positives say the value too.
  for (const std::string value : {"nan", "1e9", "0", "-1"}) {
    const SageRun bench = RunSage({"bench", "scale", "--vehicles", "1", "--duration", value});
    EXPECT_EQ(bench.status, 2) << value;
    EXPECT_NE(bench.err.find("sage: error: bench scale: --duration = " + value + ": must be > 0 and <= 604800 s (a week)"),
              std::string::npos)
        << bench.err;
  }
  // Under one control cycle of the fields it would generate (10 Hz), and of the file given, said
  // of the option.
  const SageRun short_bench = RunSage({"bench", "scale", "--vehicles", "1", "--duration", "0.04"});
  EXPECT_EQ(short_bench.status, 2);
  EXPECT_NE(short_bench.err.find("--duration = 0.04: must fly at least one control cycle (>= 0.05 s at control_rate_hz "
                                 "= 10"),
            std::string::npos)
      << short_bench.err;
  const SageRun short_run = RunSage({"run", file, "--duration", "0.02"});
  EXPECT_EQ(short_run.status, 2);
  // Said as CLI11's option errors are: the command, the option, where the options are explained.
  EXPECT_NE(short_run.err.find("sage: error: run: --duration = 0.02: must fly at least one control cycle"), std::string::npos)
      << short_run.err;
  EXPECT_NE(short_run.err.find("(see sage run --help)\n"), std::string::npos) << short_run.err;
  const SageRun hosts = RunSage({"launch", file, "--hosts", "0"});
  EXPECT_NE(hosts.err.find("sage: error: launch: --hosts = 0: must be > 0"), std::string::npos) << hosts.err;
  const SageRun five = RunSage({"run", file, "--weight-exponent", "5"});
  EXPECT_EQ(five.status, 2);
  EXPECT_NE(five.err.find("sage: error: run: --weight-exponent = 5: must be a number in [0, 4] (see sage run --help)"),
            std::string::npos)
      << five.err;
  const SageRun seed = RunSage({"run", file, "--seed", "-3"});
  EXPECT_EQ(seed.status, 2);
  EXPECT_NE(seed.err.find("--seed = -3: must be a whole number >= 0"), std::string::npos) << seed.err;
  // An option the command does not have is named, with the nearest it has (CLI11 had said "The
  // following arguments were not expected: 20 --durations").
  const SageRun typo = RunSage({"run", file, "--durations", "20"});
  EXPECT_EQ(typo.status, 2);
  EXPECT_NE(typo.err.find("sage: error: run: --durations: no such option; did you mean --duration? (see sage run --help)"),
            std::string::npos)
      << typo.err;
  const SageRun nested = RunSage({"bench", "leaks", file, "--run", "5"});
  EXPECT_EQ(nested.status, 2);
  EXPECT_NE(nested.err.find("bench leaks: --run: no such option; did you mean --runs?"), std::string::npos) << nested.err;
  // Unknown options are said before anything CLI11 stopped at, and an option with no value says
  // what it wants; compare names why it has no --controller.
  const SageRun helpp = RunSage({"run", "--helpp"});
  EXPECT_NE(helpp.err.find("run: --helpp: no such option; did you mean --help?"), std::string::npos) << helpp.err;
  const SageRun bare = RunSage({"run", file, "--duration"});
  EXPECT_NE(bare.err.find("run: --duration: needs a number after it"), std::string::npos) << bare.err;
  const SageRun both = RunSage({"compare", file, "-c", "astar"});
  EXPECT_NE(both.err.find("compare: -c: no such option; compare flies both controllers"), std::string::npos) << both.err;
  // A launch's domain past the secured range says both ranges (0..232 had been followed by 0..230).
  const SageRun domain = RunSage({"launch", file, "--domain", "999"});
  EXPECT_EQ(domain.status, 2);
  EXPECT_NE(domain.err.find("--domain = 999: must be in 0..232 (0..230 for a secured mission, the default)"),
            std::string::npos)
      << domain.err;
  // A host's is plain DDS unless --security: not said to be secured by default.
  const SageRun host_domain = RunSage({"agents", file, "--domain", "300"});
  EXPECT_EQ(host_domain.status, 2);
  EXPECT_NE(host_domain.err.find("--domain = 300: must be in 0..232 (0..230 for a secured mission: --security)"),
            std::string::npos)
      << host_domain.err;
  // An option given twice is said so (CLI11's "At Most 1 required but received 2" had read as
  // if a second value were wanted).
  const SageRun twice = RunSage({"run", file, "--duration", "30", "--duration", "60"});
  EXPECT_EQ(twice.status, 2);
  EXPECT_NE(twice.err.find("sage: error: run: --duration: given 2 times; give it once (see sage run --help)"),
            std::string::npos)
      << twice.err;
  // `vehicle add 2 --count 3` names the two ways the count came ("--count: given 2 times" had
  // named one option, given once); parsing fails before any mission is looked for.
  const SageRun count_twice = RunSage({"vehicle", "add", "2", "--count", "3"});
  EXPECT_EQ(count_twice.status, 2);
  EXPECT_NE(count_twice.err.find("sage: error: vehicle add: the count was given 2 times (the argument, --count and -c "
                                 "are one option); give it once (see sage vehicle add --help)"),
            std::string::npos)
      << count_twice.err;
  // A flag's help shows no CLI11 default ("--no-latest{false}" had).
  const SageRun launch_help = RunSage({"launch", "--help"});
  EXPECT_EQ(launch_help.status, 0);
  EXPECT_NE(launch_help.out.find("--no-latest"), std::string::npos) << launch_help.out;
  EXPECT_EQ(launch_help.out.find("{false}"), std::string::npos) << launch_help.out;
  // A value that is no number says what was wanted (CLI11's "Could not convert: --duration = abc" had not).
  const SageRun word = RunSage({"run", file, "--duration", "abc"});
  EXPECT_EQ(word.status, 2);
  EXPECT_NE(word.err.find("sage: error: run: --duration = abc: must be a number (see sage run --help)"), std::string::npos)
      << word.err;
  const SageRun half = RunSage({"field", "generate", "--xts", "2.5", "-o", "unused.yaml"});
  EXPECT_EQ(half.status, 2);
  EXPECT_NE(half.err.find("--xts = 2.5: must be a whole number"), std::string::npos) << half.err;
  // field generate: the sensors by name, and a folder that is not there, each one line.
  const SageRun lidar = RunSage({"field", "generate", "--sensors", "lidar", "-o", "unused.yaml"});
  EXPECT_EQ(lidar.status, 2);
  EXPECT_NE(lidar.err.find("--sensors = lidar: must be none, camera or camera+sonar"), std::string::npos) << lidar.err;
  const std::string nowhere = (std::filesystem::temp_directory_path() / "sage_no_such_folder_x9" / "f.yaml").string();
  const SageRun missing = RunSage({"field", "generate", "--xts", "3", "-o", nowhere});
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("--out = " + nowhere + ": its folder"), std::string::npos) << missing.err;
  EXPECT_NE(missing.err.find("does not exist"), std::string::npos) << missing.err;
  // A risk change's source is a name: not empty, no line of its own (refused before any mission is looked for).
  for (const std::string& source : {std::string(""), std::string("ops\ndesk")}) {
    const SageRun said = RunSage({"risk", "set", "P1", "2", "--source", source});
    EXPECT_EQ(said.status, 2) << source;
    EXPECT_NE(said.err.find("risk set: --source: must be 1 to 64 characters"), std::string::npos) << said.err;
  }
  // Nor the mission's own name for its changes, nor a spreadsheet formula.
  const SageRun own = RunSage({"risk", "set", "P1", "2", "--source", "scenario"});
  EXPECT_EQ(own.status, 2);
  EXPECT_NE(own.err.find("risk set: --source: 'scenario' is the mission's own"), std::string::npos) << own.err;
  // A weight is a decimal number as typed: an empty one (an unset shell variable) had set the
  // valve's risk to 0, and hex or padded ones had been taken.
  for (const std::string& weight : {std::string(""), std::string(" 2"), std::string("0x10"), std::string("2x")}) {
    const SageRun said = RunSage({"risk", "set", "P1", weight, "--mission", "/nonexistent_sage_mission"});
    EXPECT_EQ(said.status, 2) << weight;
    EXPECT_NE(said.err.find("risk set: weight = " + weight + ": must be a number in [0, "), std::string::npos) << said.err;
  }
}


// `sage launch --resume` goes on with the controller and time scale of the mission's own
// mission.json: a -c or --time-scale given with it is refused by name (both had been taken and
// ignored in silence), before the run directory is read; with neither, the same directory gets
// past that door to the run directory's own checks.
TEST(ScenarioOverrides, ResumeRefusesAControllerOrTimeScale) {
  const std::string dir = (std::filesystem::temp_directory_path() / "sage_resume_options_test").string();
  std::filesystem::remove_all(dir);
  const auto launch = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = {"launch", "--resume", dir};
    args.insert(args.end(), extra.begin(), extra.end());
    const SageRun run = RunSage(args);
    return std::make_pair(run.status, run.err);
  };
  for (const auto& [extra, name] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"-c", "astar"}, "--controller"},
           {{"--controller", "ergodic"}, "--controller"},
           {{"--time-scale", "4"}, "--time-scale"},
           {{"--time-scale", "4", "-c", "astar"}, "--controller"}}) {
    const auto [status, err] = launch(extra);
    EXPECT_EQ(status, 2) << name;
    EXPECT_NE(err.find("give no " + name + " with it"), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;  // one line
  }
  const auto [status, err] = launch({});
  EXPECT_NE(status, 0);
  EXPECT_EQ(err.find("give no"), std::string::npos) << err;
  EXPECT_FALSE(std::filesystem::exists(dir));
}


nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// `sage run` stopped by a signal (Ctrl-C: the flag its handler sets) ends where it is with its
// whole run directory, as a launch does: the table, the final metrics.json (complete,
// stopped_early, the time flown), the charts, the effective scenario cut to that time, no
// checkpoint left behind; status 130. Not stopped, the same mission runs to its duration.
TEST(RunStop, AStoppedRunWritesItsWholeRecord) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sage_run_stop_test";
  std::filesystem::remove_all(dir);
  RunCommand c;
  c.scenario.scenario_path = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
  c.scenario.duration_s = 3.0;
  c.out_dir = dir.string();
  std::atomic<bool> stop{true};  // as though Ctrl-C came during the first cycle
  c.stop = &stop;
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(CmdRun(c), 130);
  const std::string table = testing::internal::GetCapturedStdout(), said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("stopped by a signal at t = 0.1 s of 3 s"), std::string::npos) << said;
  EXPECT_NE(table.find("longest gap"), std::string::npos) << table;  // the table: on stdout, alone
  EXPECT_EQ(table.find("[warning]"), std::string::npos) << table;
  nlohmann::json m = ReadJson(dir / "metrics.json");
  EXPECT_TRUE(m.at("complete").get<bool>());
  EXPECT_TRUE(m.at("stopped_early").get<bool>());
  EXPECT_NEAR(m.at("duration_s").get<double>(), 0.1, 1e-9);
  for (const char* name : {"plot.svg", "plot.png", "metric.svg", "revisits.svg", "seabed.bt", "risk.ot", "scenario.yaml"})
    EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
  EXPECT_FALSE(std::filesystem::exists(dir / "checkpoint.bin"));
  EXPECT_NEAR(maps::LoadScenario((dir / "scenario.yaml").string()).duration_s, 0.1, 1e-9);

  stop = false;
  testing::internal::CaptureStderr();
  EXPECT_EQ(CmdRun(c), 0);
  // Into the same directory again: said, not done in silence.
  EXPECT_NE(testing::internal::GetCapturedStderr().find("replacing the run recorded there"), std::string::npos);
  m = ReadJson(dir / "metrics.json");
  EXPECT_FALSE(m.at("stopped_early").get<bool>());
  EXPECT_NEAR(m.at("duration_s").get<double>(), 3.0, 1e-9);
  std::filesystem::remove_all(dir);
}


// --profile becomes the effective scenario's default profile, so the run directory's
// scenario.yaml flies (and `sage evaluate` scores) the profile the run flew: it had kept the
// file's default, and `sage run DIR/scenario.yaml` flew one_extreme after a run of graded.
TEST(ScenarioOverrides, TheProfileGivenIsTheEffectiveScenariosDefault) {
  ScenarioOverrides o;
  o.scenario_path = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
  EXPECT_EQ(LoadWithOverrides(o).default_profile, "one_extreme");
  o.profile = "graded";
  const maps::Scenario effective = LoadWithOverrides(o);
  EXPECT_EQ(effective.default_profile, "graded");
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "sage_effective_profile_test.yaml";
  std::ofstream(file) << maps::EmitScenario(effective);
  const maps::Scenario again = maps::LoadScenario(file.string());
  EXPECT_EQ(again.default_profile, "graded");
  EXPECT_EQ(again.ProfileWeights(again.ProfileOrThrow("")), effective.ProfileWeights(effective.ProfileOrThrow("graded")));
  std::filesystem::remove(file);
}


// An A* tour mission warns of the options that shape only the ergodic fleet (a new user's
// `-c astar -K 5` had run without a word, and `-c astar --assignment regions` too); the ergodic
// fleet of --order, and of region options when it is not split into regions. None given, nothing to say.
TEST(ScenarioOverrides, NamesTheOptionsGivenAndNotUsed) {
  const maps::Scenario shared = maps::LoadScenario(kFleetField);  // assignment: shared
  ASSERT_NE(shared.fleet.assignment, maps::FleetAssignment::kRegions);
  maps::Scenario regions = shared;
  regions.fleet.assignment = maps::FleetAssignment::kRegions;
  ScenarioOverrides o;
  for (const Flown flown : {Flown::kErgodic, Flown::kTours, Flown::kBoth}) EXPECT_TRUE(UnusedOverrides(o, shared, flown).empty());
  o.duration_s = 30.0;
  o.guard = "off";
  o.weight_exponent = 0.5;  // the SMC target's and the tours' waits: used by both
  for (const Flown flown : {Flown::kErgodic, Flown::kTours, Flown::kBoth}) EXPECT_TRUE(UnusedOverrides(o, shared, flown).empty());
  o.basis_order = 5;
  EXPECT_EQ(UnusedOverrides(o, shared, Flown::kTours),
            std::vector<std::string>{"--basis-order: the ergodic controller's; -c astar flies tours without it (given, not used)"});
  EXPECT_TRUE(UnusedOverrides(o, shared, Flown::kErgodic).empty());
  EXPECT_TRUE(UnusedOverrides(o, shared, Flown::kBoth).empty());
  o.forgetting_time_s = 10.0;
  o.min_turn_radius_m = 0.2;
  ASSERT_EQ(UnusedOverrides(o, shared, Flown::kTours).size(), 1u);
  EXPECT_EQ(UnusedOverrides(o, shared, Flown::kTours)[0].rfind("--basis-order, --forgetting, --turn-radius: ", 0), 0u);
  o = ScenarioOverrides{};
  o.steer = "posterior";  // a tour moves for no detection
  EXPECT_EQ(UnusedOverrides(o, shared, Flown::kTours),
            std::vector<std::string>{"--steer: the ergodic controller's; -c astar flies tours without it (given, not used)"});
  // The tour planner shares the valves out, whatever the ergodic fleet's assignment.
  o = ScenarioOverrides{};
  o.assignment = "regions";
  o.age_weighting_laps = 2.0;
  ASSERT_EQ(UnusedOverrides(o, regions, Flown::kTours).size(), 1u);
  EXPECT_EQ(UnusedOverrides(o, regions, Flown::kTours)[0].rfind("--assignment, --age-weighting: ", 0), 0u);
  EXPECT_TRUE(UnusedOverrides(o, regions, Flown::kErgodic).empty());
  EXPECT_TRUE(UnusedOverrides(o, regions, Flown::kBoth).empty());
  // Region options on a shared fleet: unused by the ergodic fleet, and no advice to tours.
  o = ScenarioOverrides{};
  o.risk_share = 0.3;
  for (const Flown flown : {Flown::kErgodic, Flown::kBoth}) {
    ASSERT_EQ(UnusedOverrides(o, shared, flown).size(), 1u);
    EXPECT_NE(UnusedOverrides(o, shared, flown)[0].find("shape regions only; this mission's assignment is shared"),
              std::string::npos);
  }
  EXPECT_EQ(UnusedOverrides(o, shared, Flown::kTours).size(), 1u);
  EXPECT_EQ(UnusedOverrides(o, shared, Flown::kTours)[0].rfind("--risk-share: the ergodic controller's", 0), 0u);
  // --order steers the A* vehicles: unused by the ergodic fleet alone, used by a comparison.
  o = ScenarioOverrides{};
  o.order = "shortest";
  ASSERT_EQ(UnusedOverrides(o, shared, Flown::kErgodic).size(), 1u);
  EXPECT_EQ(UnusedOverrides(o, shared, Flown::kErgodic)[0].rfind("--order: ", 0), 0u);
  EXPECT_TRUE(UnusedOverrides(o, shared, Flown::kTours).empty());
  EXPECT_TRUE(UnusedOverrides(o, shared, Flown::kBoth).empty());
}


// A fleet's size against its field is said before it flies: more vehicles than valves under
// tours or regions (one a valve flies, the others are held in reserve: told, not warned; a shared
// fleet flies them all), and a warning for ergodic coverage with more than ten valves a vehicle.
TEST(FleetDensity, SaysWhenTheFleetDoesNotSuitTheField) {
  maps::Scenario field = maps::LoadScenario(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml");
  ASSERT_EQ(field.ValveCount(), 5);
  ASSERT_EQ(field.vehicles.size(), 1u);
  ASSERT_EQ(field.fleet.assignment, maps::FleetAssignment::kShared);
  for (const Flown flown : {Flown::kErgodic, Flown::kTours, Flown::kBoth}) EXPECT_EQ(FleetDensityNote(field, flown).text, "");
  const maps::VehicleSpec spare = field.vehicles.front();
  field.vehicles.resize(5, spare);  // five: one a valve, none held
  for (const Flown flown : {Flown::kErgodic, Flown::kTours, Flown::kBoth}) EXPECT_EQ(FleetDensityNote(field, flown).text, "");
  field.vehicles.push_back(spare);  // six for five valves
  EXPECT_EQ(FleetDensityNote(field, Flown::kErgodic).text, "");  // shared
  const FleetNote tours = FleetDensityNote(field, Flown::kTours);
  EXPECT_FALSE(tours.warning);
  EXPECT_EQ(tours.text.rfind("6 vehicles for 5 valves: tours fly one vehicle a valve and hold the other 1 in reserve", 0), 0u)
      << tours.text;
  field.fleet.assignment = maps::FleetAssignment::kRegions;
  EXPECT_EQ(FleetDensityNote(field, Flown::kErgodic).text.rfind("6 vehicles for 5 valves: regions fly", 0), 0u);
  EXPECT_NE(FleetDensityNote(field, Flown::kErgodic).text.find("(--assignment shared flies them all)"), std::string::npos);
  EXPECT_EQ(FleetDensityNote(field, Flown::kBoth).text.rfind("6 vehicles for 5 valves: regions and tours fly", 0), 0u);
  // Sparse: 11 valves a vehicle under regions, a warning; tours are what it advises, so tours
  // are not warned.
  maps::Scenario sparse = maps::LoadScenario(kFleetField);  // 20 valves
  sparse.fleet.assignment = maps::FleetAssignment::kRegions;
  sparse.vehicles.resize(2);
  while (sparse.ValveCount() <= 20) sparse.structures.push_back(sparse.structures.front());
  const int valves = sparse.ValveCount();
  EXPECT_EQ(FleetDensityNote(sparse, Flown::kTours).text, "");
  const FleetNote warned = FleetDensityNote(sparse, Flown::kErgodic);
  EXPECT_TRUE(warned.warning);
  EXPECT_EQ(warned.text.rfind(fmt::format("{} valves for 2 vehicles", valves), 0), 0u) << warned.text;
  // As sparse flying one shared target, and with one vehicle (one on 200 valves had left 147
  // unseen, unwarned): warned alike.
  sparse.vehicles.resize(1);
  EXPECT_EQ(FleetDensityNote(sparse, Flown::kErgodic).text.rfind(fmt::format("{} valves for 1 vehicle (", valves), 0), 0u)
      << FleetDensityNote(sparse, Flown::kErgodic).text;
  sparse.vehicles.resize(2);
  sparse.fleet.assignment = maps::FleetAssignment::kShared;
  EXPECT_TRUE(FleetDensityNote(sparse, Flown::kErgodic).warning);
  EXPECT_EQ(FleetDensityNote(sparse, Flown::kTours).text, "");
}


// sage evaluate says where its figures do not rest on the record: a --duration past the last
// sample (every gap runs on to it), and the profile's events after the evaluated end.
TEST(EvaluateWarnings, SaysWhatGoesBeyondTheRecord) {
  const std::filesystem::path csv = std::filesystem::temp_directory_path() / "sage_evaluate_warnings_test.csv";
  std::ofstream(csv) << "t,vehicle,x,y\n0,0,0.6,0.6\n0.1,0,0.65,0.6\n0.2,0,0.7,0.6\n";
  const auto warnings = [&](const std::string& profile, std::optional<double> duration) {
    EvaluateCommand c;
    c.trajectory_path = csv.string();
    c.scenario_path = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
    c.profile = profile;
    c.duration_s = duration;
    testing::internal::CaptureStderr();
    EXPECT_EQ(CmdEvaluate(c), 0);
    const std::string out = testing::internal::GetCapturedStderr();
    std::string lines;
    std::istringstream in(out);
    for (std::string line; std::getline(in, line);)
      if (line.find("[warning]") != std::string::npos) lines += line + "\n";
    return lines;
  };
  EXPECT_EQ(warnings("", std::nullopt), "");
  EXPECT_EQ(warnings("", 0.2), "");
  EXPECT_NE(warnings("", 50.0).find("--duration = 50: past the trajectory's last sample (t = 0.2 s)"), std::string::npos);
  EXPECT_NE(warnings("leak_injection", std::nullopt).find("1 risk event(s) of profile leak_injection come after"),
            std::string::npos);
  EXPECT_EQ(warnings("leak_injection", 200.0).find("risk event"), std::string::npos);  // 150 s: within
  // A record that is not of this field: most of its samples far outside two_xt's 5.6 x 4.3 m, and
  // a 500 m step in 1 s. Neither had been remarked; a record on the field (above) says neither.
  std::ofstream(csv) << "t,vehicle,x,y\n0,0,0.6,0.6\n1,0,11,8\n2,0,11.5,8\n3,0,511.5,8\n";
  const std::string foreign = warnings("", std::nullopt);
  EXPECT_NE(foreign.find("3 of its 4 samples (75.0 %) lie more than 1 m outside the workspace"), std::string::npos)
      << foreign;
  EXPECT_NE(foreign.find("2 step(s) faster than 2.4 m/s"), std::string::npos) << foreign;
  EXPECT_NE(foreign.find("the fastest 500 m in 1 s, vehicle 0 at t = 3.0 s"), std::string::npos) << foreign;
  // A thinned record (trajectory_rate_hz 2 of two_xt's 10 Hz), whichever scenario is given: said
  // from the rows' own spacing; the record at the control rate above says nothing of it.
  std::ofstream(csv) << "t,vehicle,x,y\n0,0,0.6,0.6\n0,1,1,1\n0.5,0,0.9,0.6\n0.5,1,1.3,1\n1,0,1.2,0.6\n1,1,1.6,1\n";
  const std::string thinned = warnings("", std::nullopt);
  EXPECT_NE(thinned.find("a vehicle's rows are 0.5 s apart (the median), the scenario's control cycle 0.1 s: a pass "
                         "between two rows is not seen"),
            std::string::npos)
      << thinned;
  // A hole in a vehicle's rows (a row at 60 s after a log that ended at 0.5 s) is said, with what
  // the evaluation makes of it; rows at the control rate throughout say nothing of holes.
  {
    std::ofstream hole(csv);
    hole << "t,vehicle,x,y\n";
    for (int i = 0; i <= 5; ++i) hole << 0.1 * i << ",rov1," << 0.6 + 0.05 * i << ",0.6\n";
    hole << "60,rov1,0.9,0.6\n";
  }
  const std::string holed = warnings("", std::nullopt);
  EXPECT_NE(holed.find("rov1 has no rows from t = 0.5 s to 60.0 s (59.5 s; the record's rows are 0.1 s apart otherwise): "
                       "it counts as where it was at 0.5 s all through"),
            std::string::npos)
      << holed;
  // Vehicles by name: one the scenario names says nothing; others are named in the warning (a
  // misspelt log had gone unremarked). two_xt flies rov1.
  std::ofstream(csv) << "t,vehicle,x,y\n0,rov1,0.6,0.6\n0.1,rov1,0.65,0.6\n";
  EXPECT_EQ(warnings("", std::nullopt), "");
  std::ofstream(csv) << "t,vehicle,x,y\n0,rov1,0.6,0.6\n0,rvo2,1,1\n0.1,rov1,0.65,0.6\n0.1,rvo2,1,1.05\n";
  const std::string strangers = warnings("", std::nullopt);
  EXPECT_NE(strangers.find("1 of its 2 vehicle(s) not named in "), std::string::npos) << strangers;
  EXPECT_NE(strangers.find("two_xt.yaml (rvo2): a record of another fleet"), std::string::npos) << strangers;
  std::filesystem::remove(csv);
}


// An operator command for a mission whose record is complete says at once that it has ended,
// naming its directory (it had waited 3-6 s for an answer and named only the DDS domain), with
// status 1 (no mission to take it), for each command.
TEST(OperatorDoor, AnEndedMissionIsSaidAtOnce) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sage_ended_mission_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  MissionFile m;
  m.domain_id = 7;
  m.run_dir = dir.string();
  m.scenario_path = (dir / "scenario.yaml").string();
  WriteMissionFile(dir.string(), m);
  std::ofstream(dir / "trajectory.csv") << "t,vehicle,x,y\n0,0,1,1\n12.5,0,1.5,1\n";
  std::ofstream(dir / "metrics.json") << R"({"complete": true, "duration_s": 12.5})";
  for (const std::vector<std::string>& command :
       std::vector<std::vector<std::string>>{{"stop"}, {"risk", "set", "P1", "2"}, {"vehicle", "remove", "0"}, {"vehicle", "add"},
                                                {"vehicle", "add", "2"}}) {
    std::vector<std::string> args = command;
    args.insert(args.end(), {"--mission", dir.string()});
    const SageRun run = RunSage(args);
    EXPECT_EQ(run.status, 1) << command.front();
    EXPECT_NE(run.err.find("the mission in " + dir.string() + " has ended (its record is complete, to t = 12.5 s)"),
              std::string::npos)
        << run.err;
  }
  // Status only reads: an ended mission is told with its figures, status 0 (it had been refused
  // as the commands above are).
  std::ofstream(dir / "metrics.json") << R"({"complete": true, "duration_s": 12.5, "stopped_early": true,
      "vehicle_count": 4, "unvisited_valves": 2, "valves": [{}, {}, {}, {}, {}], "risk_weighted_interval_s": 8.26,
      "longest_gap_s": {"median": 3, "p90": 5, "max": 9.04}})";
  const SageRun ended = RunSage({"status", "--mission", dir.string()});
  EXPECT_EQ(ended.status, 0) << ended.err;
  EXPECT_NE(ended.out.find("mission in " + dir.string() + ": ended (stopped early) at t = 12.5 s; 4 vehicle(s); "
                           "unvisited valves 2 of 5; risk-weighted interval >= 8.3 s; longest gap 9.0 s"),
            std::string::npos)
      << ended.out << ended.err;
  // Launched, unfinished, its launcher gone (a server that died): said at once, with the resume
  // (it had waited 3 s and said only that no mission listened on its domain).
  const pid_t gone = fork();
  if (gone == 0) _exit(0);
  ASSERT_GT(gone, 0);
  waitpid(gone, nullptr, 0);
  m.launcher_pid = gone;
  WriteMissionFile(dir.string(), m);
  std::ofstream(dir / "metrics.json") << R"({"complete": false, "duration_s": 12.5})";
  const SageRun stopped = RunSage({"stop", "--mission", dir.string()});
  EXPECT_EQ(stopped.status, 1);
  const std::string& err = stopped.err;
  EXPECT_NE(err.find("the mission in " + dir.string() + " is not running: its server is gone and no sage launch runs it " +
                     "(its record stops at t = 12.5 s"),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("resume it with sage launch --resume " + dir.string()), std::string::npos) << err;
  std::filesystem::remove_all(dir);
}

// A scenario whose seabed map is refused leaves --out as it was: an earlier run there keeps its
// record (it had been cut to a stub holding the refused scenario), and no directory is made.
TEST(OutDirectory, ARefusedSeabedTouchesNoRunDirectory) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_refused_seabed_test";
  fs::remove_all(root);
  fs::create_directories(root / "earlier");
  const std::string source = std::string(SAGE_SOURCE_DIR) + "/scenarios/";
  fs::copy_file(source + "manifold_slope.xyz", root / "manifold_slope.xyz");
  std::ifstream in(source + "manifold_slope.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string origin = "origin_m: [431182, 6478282]";
  ASSERT_NE(text.find(origin), std::string::npos);
  text.replace(text.find(origin), origin.size(), "origin_m: [431182, 6478200]");  // the map no longer covers it
  std::ofstream(root / "shifted.yaml") << text;
  std::ofstream(root / "earlier" / "metrics.json") << R"({"complete": true})";
  std::ofstream(root / "earlier" / "trajectory.csv") << "t,vehicle,x,y\n0,0,1,1\n";
  const std::string scenario = (root / "shifted.yaml").string();
  for (const std::string command : {"run", "compare"}) {
    const SageRun refused = RunSage({command, scenario, "--duration", "5", "-o", (root / "earlier").string()});
    EXPECT_EQ(refused.status, 2) << command;
    EXPECT_NE(refused.err.find("the map must cover the workspace"), std::string::npos) << refused.err;
    EXPECT_EQ(refused.err.find("replacing"), std::string::npos) << refused.err;
    const SageRun fresh = RunSage({command, scenario, "--duration", "5", "-o", (root / "new").string()});
    EXPECT_EQ(fresh.status, 2) << command;
    EXPECT_FALSE(fs::exists(root / "new")) << command << " made the run directory of a refused mission";
  }
  std::vector<std::string> kept;
  for (const auto& entry : fs::directory_iterator(root / "earlier")) kept.push_back(entry.path().filename().string());
  std::sort(kept.begin(), kept.end());
  EXPECT_EQ(kept, (std::vector<std::string>{"metrics.json", "trajectory.csv"}));
  std::ifstream metrics(root / "earlier" / "metrics.json");
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(metrics)), std::istreambuf_iterator<char>()),
            R"({"complete": true})");
  fs::remove_all(root);
}

// A launch on an interface this machine lacks, or to a peer no resolver finds, is refused before
// its run directory, security identities or lock are made (one had left security/ behind, which
// the next launch there refused as files not a run's), naming the option given.
TEST(OutDirectory, ALaunchRefusedForItsNetworkLeavesNothing) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_refused_network_test";
  fs::remove_all(root);
  fs::create_directories(root);
  const std::string scenario = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
  const std::pair<std::vector<std::string>, std::string> cases[] = {
      {{"--interface", "sagenosuch0"}, "--interface = 'sagenosuch0': no such interface with an IPv4 address on this machine"},
      {{"--peer", "sage-no-such-host.invalid"}, "--peer = 'sage-no-such-host.invalid': no IPv4 address for that host name"},
      {{"--peer", "not..a..host"}, "sage: error: launch: --peer = not..a..host: must be an IPv4 address or a host name"},
      {{"--interface", "eth0/x"}, "sage: error: launch: --interface = eth0/x: must be a network interface name"},
  };
  for (const auto& [options, expected] : cases) {
    std::vector<std::string> args = {"launch", scenario, "--duration", "2", "--http", "off", "--foxglove", "off",
                                     "--no-latest", "--out", (root / "mission").string()};
    args.insert(args.end(), options.begin(), options.end());
    const SageRun refused = RunSage(args);
    EXPECT_EQ(refused.status, 2) << options.back() << ": " << refused.err;
    EXPECT_NE(refused.err.find(expected), std::string::npos) << refused.err;
    EXPECT_FALSE(fs::exists(root / "mission")) << options.back() << ": the refused launch made its run directory";
  }
  fs::remove_all(root);
}

// A run directory keeps its own copy of the seabed map, named relative to its scenario.yaml: it
// runs again after the map it came from is gone (the scenario had named that file by its absolute
// path), and flies the same mission.
TEST(OutDirectory, ARunKeepsItsSeabedMap) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_run_keeps_map_test";
  fs::remove_all(root);
  fs::create_directories(root / "source");
  const std::string source = std::string(SAGE_SOURCE_DIR) + "/scenarios/";
  fs::copy_file(source + "manifold_slope.xyz", root / "source" / "manifold_slope.xyz");
  fs::copy_file(source + "manifold_slope.yaml", root / "source" / "manifold_slope.yaml");
  const fs::path first = root / "first", again = root / "again";
  ASSERT_EQ(RunSage({"run", (root / "source" / "manifold_slope.yaml").string(), "--duration", "2", "-o", first.string()})
                .status,
            0);
  const auto read = [](const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  EXPECT_EQ(read(first / "seabed_map.xyz"), read(source + "manifold_slope.xyz"));
  const std::string kept = read(first / "scenario.yaml");
  EXPECT_NE(kept.find("map: seabed_map.xyz"), std::string::npos) << kept;
  EXPECT_EQ(kept.find((root / "source").string()), std::string::npos) << kept;
  fs::remove_all(root / "source");
  const SageRun rerun = RunSage({"run", (first / "scenario.yaml").string(), "-o", again.string()});
  ASSERT_EQ(rerun.status, 0) << rerun.err;
  EXPECT_EQ(read(again / "trajectory.csv"), read(first / "trajectory.csv"));
  EXPECT_EQ(read(again / "seabed_map.xyz"), read(first / "seabed_map.xyz"));
  fs::remove_all(root);
}

// A crashed launch's directory (mission.json, a record that stops short, its launcher gone) is
// refused by sage run, compare and evaluate -o as sage launch refuses it: a new user's `sage run
// -o` there had replaced its checkpoint and record with only a warning. Finished, it may be reused.
TEST(OutDirectory, ACrashedLaunchIsNotWrittenOver) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "sage_crashed_launch_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const pid_t gone = fork();
  if (gone == 0) _exit(0);
  ASSERT_GT(gone, 0);
  waitpid(gone, nullptr, 0);
  MissionFile m;
  m.domain_id = 7;
  m.run_dir = dir.string();
  m.scenario_path = (dir / "scenario.yaml").string();
  m.launcher_pid = gone;
  WriteMissionFile(dir.string(), m);
  const std::string record = "t,vehicle,x,y\n0,0,1,1\n12.5,0,1.5,1\n";
  std::ofstream(dir / "trajectory.csv") << record;
  std::ofstream(dir / "metrics.json") << R"({"complete": false, "duration_s": 12.5})";
  const std::string scenario = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
  for (const std::string command : {"run", "compare"}) {
    const SageRun refused = RunSage({command, scenario, "--duration", "5", "-o", dir.string()});
    EXPECT_EQ(refused.status, 2) << command;
    EXPECT_NE(refused.err.find("--out = " + dir.string() + ": it holds a mission that did not finish (recorded to t = 12.5 s"),
              std::string::npos)
        << refused.err;
    EXPECT_NE(refused.err.find("resume it with sage launch --resume " + dir.string()), std::string::npos) << refused.err;
  }
  std::ifstream kept(dir / "trajectory.csv");
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(kept)), std::istreambuf_iterator<char>()), record);
  EXPECT_FALSE(fs::exists(dir / "ergodic")) << "compare made its runs' directories";
  // The same directory, its mission finished: a new run may replace it (with the warning).
  std::ofstream(dir / "metrics.json") << R"({"complete": true, "duration_s": 12.5})";
  const SageRun again = RunSage({"run", scenario, "--duration", "5", "-o", dir.string()});
  EXPECT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find("replacing the run recorded there"), std::string::npos) << again.err;
  fs::remove_all(dir);
}

// compare's calibration of the A* wait says when it cannot match the ergodic run's time at the
// dominant valve: a wait longer than the mission (two valves, 10 s: the tour would sit at its
// first valve) is warned of, and where the ergodic vehicle never reached that valve (one vehicle,
// 200 valves, 20 s) the scenario's wait is kept and said to be (both had read as matched).
TEST(Compare, ACalibrationThatCannotMatchSaysSo) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_compare_calibration_test";
  fs::remove_all(root);
  fs::create_directories(root);
  const std::string two = (root / "two.yaml").string(), many = (root / "many.yaml").string();
  ASSERT_EQ(RunSage({"field", "generate", "--xts", "1", "--valves", "2", "--vehicles", "1", "-o", two}).status, 0);
  ASSERT_EQ(RunSage({"field", "generate", "--xts", "50", "--valves", "200", "--vehicles", "1", "-o", many}).status, 0);
  const SageRun short_one = RunSage({"compare", two, "--duration", "10", "-o", (root / "c2").string()});
  EXPECT_EQ(short_one.status, 0) << short_one.err;
  EXPECT_NE(short_one.err.find("longer than the 10 s mission, so the tour barely flies"), std::string::npos)
      << short_one.err;
  const SageRun sparse = RunSage({"compare", many, "--duration", "20", "-o", (root / "c200").string()});
  EXPECT_EQ(sparse.status, 0) << sparse.err;
  EXPECT_NE(sparse.err.find("A* wait per lap left at the scenario's 1.00 s: ergodic control never came within the "
                            "visit radius of"),
            std::string::npos)
      << sparse.err;
  EXPECT_EQ(sparse.err.find("calibrating"), std::string::npos) << "no A* mission is flown to match nothing";
  fs::remove_all(root);
}

// A mission's own record is not written over by evaluate -o (it had replaced the run's metrics.json,
// counted every cycle, with a re-scoring under another profile, silently) nor by compare -o (it
// put astar/ and ergodic/ beside the run's files); an evaluation's own directory is replaced with
// a word; `-o ""` is refused rather than taken for the default run directory.
TEST(OutDirectory, AMissionsRecordIsNotEvaluatedOrComparedOver) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_record_kept_test";
  fs::remove_all(root);
  const std::string scenario = std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml";
  const fs::path run = root / "run";
  ASSERT_EQ(RunSage({"run", scenario, "--duration", "3", "-o", run.string()}).status, 0);
  const auto read = [](const fs::path& file) {
    std::ifstream in(file);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const std::string metrics = read(run / "metrics.json");
  const std::string csv = (run / "trajectory.csv").string();
  const SageRun over = RunSage({"evaluate", csv, "-s", scenario, "-p", "graded", "-o", run.string()});
  EXPECT_EQ(over.status, 2) << over.err;
  EXPECT_NE(over.err.find("--out = " + run.string() + ": holds a mission's record (trajectory.csv), whose metrics.json "
                          "and charts are its own; give the evaluation a directory of its own"),
            std::string::npos)
      << over.err;
  EXPECT_EQ(over.out, "") << "scored before the directory was refused";
  EXPECT_EQ(read(run / "metrics.json"), metrics);
  const SageRun compared = RunSage({"compare", scenario, "--duration", "3", "-o", run.string()});
  EXPECT_EQ(compared.status, 2) << compared.err;
  EXPECT_NE(compared.err.find("give the comparison a directory of its own"), std::string::npos) << compared.err;
  EXPECT_FALSE(fs::exists(run / "ergodic"));
  // A directory of its own: both missions, their table and which way each row is better.
  const SageRun fresh = RunSage({"compare", scenario, "--duration", "3", "--calibrate-wait", "off", "-o",
                                 (root / "compare").string()});
  EXPECT_EQ(fresh.status, 0) << fresh.err;
  EXPECT_TRUE(fs::exists(root / "compare" / "ergodic" / "metrics.json"));
  EXPECT_TRUE(fs::exists(root / "compare" / "astar" / "metrics.json"));
  EXPECT_NE(fresh.out.find("risk-weighted interval"), std::string::npos) << fresh.out;
  EXPECT_NE(fresh.out.find("\nBetter: shorter intervals, longest gaps, risk-weighted interval and exp. detection delay"),
            std::string::npos)
      << fresh.out;
  // Nor is an evaluation written into a comparison's directory, beside its two records.
  const SageRun into_compare = RunSage({"evaluate", csv, "-s", scenario, "-o", (root / "compare").string()});
  EXPECT_EQ(into_compare.status, 2) << into_compare.err;
  EXPECT_NE(into_compare.err.find("holds a mission's record (ergodic/trajectory.csv)"), std::string::npos)
      << into_compare.err;
  EXPECT_FALSE(fs::exists(root / "compare" / "metrics.json"));
  EXPECT_EQ(fresh.err.find("replacing"), std::string::npos) << fresh.err;
  // A comparison may replace an earlier one there, and says so.
  const SageRun again = RunSage({"compare", scenario, "--duration", "3", "--calibrate-wait", "off", "-o",
                                 (root / "compare").string()});
  EXPECT_EQ(again.status, 0) << again.err;
  EXPECT_NE(again.err.find((root / "compare").string() + ": replacing the comparison recorded there"), std::string::npos)
      << again.err;
  const fs::path scored = root / "graded";
  const SageRun first = RunSage({"evaluate", csv, "-s", scenario, "-p", "graded", "-o", scored.string()});
  EXPECT_EQ(first.status, 0) << first.err;
  EXPECT_EQ(first.err.find("replacing"), std::string::npos) << first.err;
  const SageRun second = RunSage({"evaluate", csv, "-s", scenario, "-p", "equal", "-o", scored.string()});
  EXPECT_EQ(second.status, 0) << second.err;
  EXPECT_NE(second.err.find(scored.string() + ": replacing the metrics.json and charts written there"), std::string::npos)
      << second.err;
  EXPECT_NE(read(scored / "metrics.json").find("\"profile\": \"equal\""), std::string::npos);
  for (const std::string command : {"run", "compare", "launch"}) {
    const SageRun empty = RunSage({command, scenario, "--duration", "3", "-o", ""});
    EXPECT_EQ(empty.status, 2) << command;
    EXPECT_NE(empty.err.find("--out = \"\": must be a path (leave the option out for the default)"), std::string::npos)
        << empty.err;
  }
  fs::remove_all(root);
}

// What a mission's settings would silently lose is said before it flies: hidden leaks with no
// sensor to see them (the table had read "detected never" as a fleet that missed them), fusion
// settings with no sensors, a sensor rate off the control cycles.
TEST(LossySettings, AreWarnedOfBeforeTheMission) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_lossy_settings_test";
  fs::remove_all(root);
  fs::create_directories(root);
  std::ifstream in(std::string(SAGE_SOURCE_DIR) + "/scenarios/two_xt.yaml");
  const std::string base((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::map<std::string, std::pair<std::string, std::string>> cases = {
      {"leaks", {"leaks: [{at: {valve: P3}, start_s: 1}]\n",
                 "leaks: 1 hidden leak(s) and no sensors: the vehicles cannot detect them"}},
      {"fusion", {"fusion: {relax_time_s: 30}\n", "fusion: the settings weigh the sensors' scans, and the vehicles carry "
                                                  "no sensors: they change nothing"}},
      {"rate", {"sensors: [{name: camera, rate_hz: 7}]\n",
                "sensors[0] (camera): rate_hz = 7: scans fall on whole control cycles (control_rate_hz = 10): it scans "
                "every cycle, at 10 Hz"}},
      {"none", {"", ""}},
  };
  for (const auto& [name, c] : cases) {
    const auto& [section, warning] = c;
    const fs::path file = root / (name + ".yaml");
    std::ofstream(file) << base << section;
    const SageRun run = RunSage({"run", file.string(), "--duration", "2", "-o", (root / ("run_" + name)).string()});
    EXPECT_EQ(run.status, 0) << name << ": " << run.err;
    if (warning.empty()) {
      EXPECT_EQ(run.err.find("[warning]"), std::string::npos) << run.err;
    } else {
      EXPECT_NE(run.err.find("[warning] " + warning), std::string::npos) << name << ": " << run.err;
    }
  }
  fs::remove_all(root);
}

// A fleet over 1,000 vehicles recording every 10 Hz cycle (a generated field at --trajectory-rate
// 0, or one grown by -n) is told the record's size and the rate that keeps ~10,000 rows a second,
// before anything is written; the generated field as written is not.
TEST(LargeRecord, IsWarnedOfWithTheRateThatKeepsItSmall) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_large_record_test";
  fs::remove_all(root);
  fs::create_directories(root);
  maps::FieldOptions options;
  options.xts = 30;
  options.valves = 90;
  options.vehicles = 2500;  // rows every 3 cycles as generated
  const fs::path field = root / "field.yaml";
  std::ofstream(field) << maps::EmitScenario(maps::GenerateField(options));
  // A file where the run directory would go: refused after the warnings, before any mission.
  const fs::path blocker = root / "not_a_directory";
  std::ofstream(blocker) << "x";
  const SageRun full = RunSage({"run", field.string(), "--trajectory-rate", "0", "-o", blocker.string()});
  EXPECT_NE(full.status, 0);
  // 2,500 vehicles x 10 Hz x 60 s x 150 bytes = 225 MB a minute; a row every 3 cycles, 75 MB.
  EXPECT_NE(full.err.find("[warning] trajectory.csv keeps every control cycle of 2500 vehicles: about 225 MB a mission "
                          "minute; --trajectory-rate 3.33333 (trajectory_rate_hz in the scenario) keeps a vehicle's row "
                          "every 3 cycles, about 75 MB a minute"),
            std::string::npos)
      << full.err;
  const SageRun as_generated = RunSage({"run", field.string(), "-o", blocker.string()});
  EXPECT_NE(as_generated.status, 0);
  EXPECT_EQ(as_generated.err.find("trajectory.csv keeps every control cycle"), std::string::npos) << as_generated.err;
  fs::remove_all(root);
}

// runs/latest names a mission that has ended (a later launch that ended first) while another
// launch runs: an operator's command that named none is told which mission runs and how to reach
// it (it had been told only that the mission had ended: start one with sage launch).
TEST(OperatorDoor, AnEndedLatestNamesTheMissionThatRuns) {
  namespace fs = std::filesystem;
  const fs::path root = fs::temp_directory_path() / "sage_latest_ended_test";
  fs::remove_all(root);
  fs::create_directories(root / "runs" / "ended");
  fs::create_directories(root / "runs" / "live");
  // A process a launcher's check takes for a running sage launch (its command line says launch).
  const pid_t launcher = fork();
  if (launcher == 0) {
    execl("/bin/sh", "sh", "-c", "while :; do sleep 1; done; : sage launch", static_cast<char*>(nullptr));
    _exit(127);
  }
  ASSERT_GT(launcher, 0);
  // Until the child has exec'd, its command line is this test's (it failed 2 runs in 6 when asked
  // at once): wait for the shell's, up to 5 s.
  const std::string cmdline_path = "/proc/" + std::to_string(launcher) + "/cmdline";
  for (int i = 0; i < 500; ++i) {
    std::ifstream in(cmdline_path, std::ios::binary);
    const std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (cmdline.find("sage launch") != std::string::npos) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  for (const auto& [name, pid] : {std::pair{"ended", 0}, std::pair{"live", static_cast<int>(launcher)}}) {
    MissionFile m;
    m.domain_id = 7;
    m.run_dir = (root / "runs" / name).string();
    m.scenario_path = (root / "runs" / name / "scenario.yaml").string();
    m.launcher_pid = pid;
    WriteMissionFile(m.run_dir, m);
  }
  std::ofstream(root / "runs" / "ended" / "trajectory.csv") << "t,vehicle,x,y\n0,0,1,1\n8,0,1.5,1\n";
  std::ofstream(root / "runs" / "ended" / "metrics.json") << R"({"complete": true, "duration_s": 8})";
  fs::create_directory_symlink(root / "runs" / "ended", root / "runs" / "latest");
  const fs::path cwd = fs::current_path();
  fs::current_path(root);
  EXPECT_EQ(RunningMissions(), std::vector<std::string>{"runs/live"});
  const SageRun told = RunSage({"risk", "set", "P1", "2"});
  const SageRun named = RunSage({"stop", "--mission", (root / "runs" / "ended").string()});
  fs::current_path(cwd);
  kill(launcher, SIGKILL);
  waitpid(launcher, nullptr, 0);
  EXPECT_EQ(told.status, 1);
  EXPECT_NE(told.err.find("has ended (its record is complete, to t = 8.0 s); a mission is running in runs/live: give "
                          "--mission runs/live"),
            std::string::npos)
      << told.err;
  // A mission named on the command line is the one meant: no other is offered.
  EXPECT_EQ(named.status, 1);
  EXPECT_EQ(named.err.find("running in"), std::string::npos) << named.err;
  fs::remove_all(root);
}

}  // namespace
}  // namespace sage::server
