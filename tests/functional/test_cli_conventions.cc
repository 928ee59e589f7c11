// One convention for every command of the `rig` tool, every rig process, benchmark and tool:
// --help on stdout with exit 0, usage errors naming the option with exit 2, --version, and
// --json - writing JSON (alone) to stdout.

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/run_rig.h"
#include "contract/channels.h"
#include "tests/support/scratch.h"

// Channel names come from the contract (functional.contract checks that no file spells them).
using nimble::contract::channels::kTruth;

using nimble::test::RigResult;
using nimble::test::run_rig;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
const std::string kBin = std::filesystem::path(RIG_BIN).parent_path().string();

/// Runs a benchmark, rig process or tool (they sit next to rig) with `args`.
RigResult run_bench(const std::string& bench, const std::string& args) {
  return nimble::test::run_program(kBin + "/" + bench, args);
}

/// The JSON written on stdout, parsed (YAML is a superset); fails the test if it does not parse.
YAML::Node json_of(const RigResult& r) {
  INFO(r.out << r.err);
  YAML::Node n;
  REQUIRE_NOTHROW(n = YAML::Load(r.out));
  REQUIRE(n.IsMap());
  return n;
}

}  // namespace

TEST_CASE(
    "cli: every command answers --help on stdout with exit 0, is in docs/tool.md, and --version names the version",
    "[cli]") {
  // The commands as `rig --help` lists them (its one table, cli/rig_main.cc).
  const RigResult help = run_rig("--help");
  REQUIRE(help.exit_code == 0);
  std::vector<std::string> commands;
  std::istringstream lines(help.out.substr(help.out.find("commands:")));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("  ", 0) != 0 || line.size() < 3 || line[2] == ' ') continue;
    commands.push_back(line.substr(2, line.find(' ', 2) - 2));
  }
  REQUIRE(commands.size() >= 15);
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/docs/tool.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  commands.push_back("discrepancy --power");
  for (const std::string& command : commands) {
    INFO(command);
    const RigResult r = run_rig(command + " --help");
    CHECK(r.exit_code == 0);
    CHECK(r.out.find("usage: rig " + command) != std::string::npos);
    CHECK(r.err.empty());
    CHECK(doc.find("| `rig " + command.substr(0, command.find(' '))) != std::string::npos);
  }
  const RigResult v = run_rig("--version");
  CHECK(v.exit_code == 0);
  CHECK(v.out.find("rig " + std::string(NIMBLE_RIG_VERSION)) == 0);
  const RigResult unknown = run_rig("--frobnicate");
  CHECK(unknown.exit_code == 2);
  CHECK(unknown.err.find("unknown command") != std::string::npos);
}

TEST_CASE("cli: usage errors name the option and exit 2, and values are checked before the command runs", "[cli]") {
  struct Case {
    std::string args;
    std::string names;  // in the message on stderr
  };
  const std::string scenario = kConfigs + "hover.yaml";
  for (const Case& c : std::vector<Case>{
           {"run " + scenario + " --bogus", "--bogus"},
           {"run", "scenario is required"},
           {"run " + scenario + " --seed -1", "--seed: '-1' is not a whole number >= 0"},
           {"run " + scenario + " --seed", "--seed"},
           {"run " + scenario + " --clock fast", "--clock: fast not in {realtime,lockstep,inprocess}"},
           {"run " + scenario + " --set duration_s", "--set: key 'duration_s'"},
           {"sweep " + scenario, "--seeds is required"},
           {"sweep " + scenario + " --seeds 1-2 --jobs 0", "--jobs"},
           {"discrepancy --power --model m.yaml --effect actuator_delay=0.01", "--scenario is required"},
           {"discrepancy --power --scenario " + scenario + " --model m.yaml --effect actuator_delay=0.01 --flights 0",
            "--flights"},
           {"export x.lcmlog --csv y.csv --rate nan", "--rate: 'nan' is not a finite number"},
           {"export x.lcmlog --format mcap", "--format mcap needs --out FILE"},
           {"export x.lcmlog --out y.mcap --rate 100", "--rate is for --format csv"},
           {"export x.lcmlog --csv y.csv --raw", "--raw is for --format mcap"},
           {"export x.lcmlog --out y.mcap --compression lz4", "--compression: lz4 not in {zstd,none}"},
           {"export x.lcmlog", "--csv FILE (or --out FILE.mcap for MCAP) is required"},
           {"turbulence x.yaml --welch-segment 1000", "--welch-segment: '1000' is not a power of two >= 8"},
           {"params nosuchsection", "section: nosuchsection not in"},
           {"model", "model is required"},
           {"reproduce", "what is required"},
           {"reproduce paper", "what: paper not in {thesis}"},
           {"reproduce thesis --states guess", "--states: guess not in {smoothed,estimate,truth}"},
           {"reproduce thesis --seeds 5-1", "--seeds 5-1: --seeds needs A-B"},
           {"reproduce thesis --set sensing", "--set: key 'sensing'"},
           {"reproduce thesis --beside", "--beside needs overrides"},
           // A regular file that is no rig log (/dev/null is refused before, as no regular file).
           {"identify " + scenario + " --states smoothed", "--states: " + scenario + " is not a rig log"},
           {"validate x.yaml " + scenario + " --states truth", "--states: " + scenario + " is not a rig log"},
           {"discrepancy " + scenario + " --model x.yaml --states smoothed",
            "--states: " + scenario + " is not a rig log"},
           {"identify x.lcmlog --states guess", "--states: guess not in {auto,estimate,truth,smoothed,sensors}"},
       }) {
    INFO(c.args);
    const RigResult r = run_rig(c.args);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(c.names) != std::string::npos);
    CHECK(r.err.find("--help' describes the options") != std::string::npos);
    CHECK(r.out.empty());
  }
  // --opt=value is the same as --opt value.
  const RigResult eq = run_rig("run " + scenario + " --clock=inprocess --set=duration_s=0.3 --no-progress --log " +
                               nimble::test::scratch_file("cli_eq", "eq.lcmlog"));
  CHECK(eq.exit_code == 0);
  CHECK(eq.out.find("clock      inprocess") != std::string::npos);
}

TEST_CASE("cli: rig reproduce thesis --dir refuses a directory made with other overrides, naming them", "[cli]") {
  // A campaign made with an override that stops its first flight short (its identification
  // fails at once, exit 2) leaves its manifest: started again with other overrides, or none, it
  // is refused before anything flies.
  const std::string dir = nimble::test::scratch_dir("cli_reproduce_dir");
  const std::string common =
      "reproduce thesis --no-progress --seeds 1 --jobs 1 --logs " + dir + "/logs --dir " + dir + "/campaign";
  const RigResult made = run_rig(common + " --set duration_s=0.05");
  INFO(made.out << made.err);
  REQUIRE(made.exit_code == 2);
  REQUIRE(std::filesystem::exists(dir + "/campaign/campaign.json"));
  const RigResult vibration = run_rig(common + " --vibration");
  CHECK(vibration.exit_code == 2);
  CHECK(vibration.err.find("holds another campaign: its overrides is [\"duration_s=0.05\"], this one's "
                           "[\"sensing.base=" +
                           std::string(RIG_SOURCE_DIR) + "/rig_configs/sensing/nimble_flight_vibration.yaml\"]") !=
        std::string::npos);
  const RigResult none = run_rig(common);
  CHECK(none.exit_code == 2);
  CHECK(none.err.find("holds another campaign: its overrides is [\"duration_s=0.05\"], this one's []") !=
        std::string::npos);
  // --beside keeps its two campaigns beside one: a directory holding one is refused.
  const RigResult beside = run_rig(common + " --vibration --beside");
  CHECK(beside.exit_code == 2);
  CHECK(beside.err.find("holds one campaign; --beside keeps its two in") != std::string::npos);
  CHECK_FALSE(std::filesystem::exists(dir + "/logs/without"));
}

TEST_CASE("cli: every benchmark answers --help on stdout with exit 0 instead of running", "[cli][programs]") {
  for (const std::string bench :
       {"bench_rig", "bench_inprocess", "bench_ident", "bench_discrepancy", "bench_ekf", "bench_turbulence",
        "bench_can", "bench_can_bridge", "bench_loop", "bench_power", "bench_export", "bench_all"}) {
    INFO(bench);
    const RigResult r = run_bench(bench, "--help");
    CHECK(r.exit_code == 0);
    CHECK(r.out.find("usage: " + bench) != std::string::npos);
  }
  const RigResult bad = run_bench("bench_ident", "many");
  CHECK(bad.exit_code == 2);
  CHECK(bad.err.find("not a number of repetitions") != std::string::npos);
}

TEST_CASE("cli: every rig process answers --help on stdout with exit 0 and names a bad option", "[cli]") {
  for (const std::string process :
       {"nimble_plant", "nimble_controller", "nimble_estimator", "nimble_mocap", "nimble_can_bridge"}) {
    INFO(process);
    const RigResult help = run_bench(process, "--help");
    CHECK(help.exit_code == 0);
    CHECK(help.out.find("usage: " + process) != std::string::npos);
    for (const std::string option : {"--scenario", "--name", "--lcm-url"}) {
      CHECK(help.out.find(option) != std::string::npos);
    }
    CHECK(help.err.empty());

    const RigResult bogus = run_bench(process, "--scenario " + kConfigs + "hover.yaml --bogus");
    CHECK(bogus.exit_code == 2);
    CHECK(bogus.err.find(process + ": ") == 0);
    CHECK(bogus.err.find("--bogus") != std::string::npos);
    CHECK(bogus.err.find("'" + process + " --help' describes the options") != std::string::npos);
    CHECK(bogus.out.empty());
  }
  const RigResult missing = run_bench("nimble_plant", "--name plant");
  CHECK(missing.exit_code == 2);
  CHECK(missing.err.find("--scenario is required") != std::string::npos);
  const RigResult no_value = run_bench("nimble_plant", "--scenario");
  CHECK(no_value.exit_code == 2);
  CHECK(no_value.err.find("--scenario") != std::string::npos);
}

TEST_CASE("cli: the calibration tools and bus_flood answer --help and check their values before running",
          "[cli][programs]") {
  for (const std::string tool : {"calibrate_pitch_gains", "calibrate_roll_map", "bus_flood"}) {
    INFO(tool);
    const RigResult r = run_bench(tool, "--help");
    CHECK(r.exit_code == 0);
    CHECK(r.out.find("usage: " + tool) != std::string::npos);
    CHECK(r.err.empty());
  }
  struct Case {
    std::string tool, args, names;
  };
  for (const Case& c : std::vector<Case>{
           {"calibrate_pitch_gains", "--kp 0.3:0.1:0.01", "--kp: range must be FROM:TO:STEP"},
           {"calibrate_pitch_gains", "--check 0.1", "--check: '0.1' is not KP,KD"},
           {"calibrate_pitch_gains", "--delay-steps 101", "--delay-steps"},
           {"calibrate_pitch_gains", "--map nan", "--map: 'nan' is not a finite number"},
           {"calibrate_roll_map", "--maps 10,x", "--maps: 'x' is not a finite number"},
           {"calibrate_roll_map", "--bogus", "--bogus"},
           {"calibrate_roll_map", "--gain-set", "--gain-set"},
           {"bus_flood", "--rate 0", "--rate"},
           {"bus_flood", "--seed -1", "--seed: '-1' is not a whole number >= 0"},
       }) {
    INFO(c.tool << " " << c.args);
    const RigResult r = run_bench(c.tool, c.args);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(c.tool + ": ") == 0);
    CHECK(r.err.find(c.names) != std::string::npos);
    CHECK(r.out.empty());
  }
}

TEST_CASE("cli: --json - writes the JSON alone to stdout (run, sweep, check, export, model)", "[cli]") {
  const std::string dir = nimble::test::scratch_dir("cli_json");
  const std::string log = dir + "/hover.lcmlog";

  const RigResult run = run_rig(
      "run " + kConfigs + "hover.yaml --clock inprocess --set duration_s=1 --no-progress --log " + log + " --json -");
  CHECK(run.exit_code == 0);
  const YAML::Node summary = json_of(run);
  CHECK(summary["result"].as<std::string>() == "ok");
  CHECK(run.err.find("== run summary: hover ==") != std::string::npos);  // the text went to stderr
  CHECK_FALSE(std::filesystem::exists("-"));

  const RigResult exported = run_rig("export " + log + " --csv " + dir + "/hover.csv --interpolation linear --json -");
  CHECK(exported.exit_code == 0);
  const YAML::Node e = json_of(exported);
  CHECK(e["samples"].as<int>() > 400);
  CHECK(e["interpolation"].as<std::string>() == "linear");

  const RigResult mcap = run_rig("export " + log + " --format mcap --out " + dir + "/hover.mcap --json -");
  CHECK(mcap.exit_code == 0);
  const YAML::Node m = json_of(mcap);
  CHECK(m["messages"].as<int>() > 1000);
  CHECK(m["channels"][kTruth]["json"].as<int>() > 100);
  CHECK(mcap.err.find("rig export: ") == 0);  // the one-line summary went to stderr

  const RigResult sweep =
      run_rig("sweep " + kConfigs + "hover.yaml --seeds 1-2 --set duration_s=0.5 --json - --jobs 1 --no-progress");
  INFO(sweep.err);
  CHECK(sweep.exit_code == 0);
  CHECK(json_of(sweep)["runs"].size() == 2);

  const RigResult check = run_rig("check --json -");
  CHECK(json_of(check)["runs_can_start"].IsDefined());

  const RigResult model = run_rig("model " + kConfigs + "models/nimble_lateral_set1.yaml --json -");
  CHECK(model.exit_code == 0);
  CHECK(json_of(model)["eigenvalues"].IsSequence());
  std::filesystem::remove_all(dir);
}

TEST_CASE("cli: rig spy without a display says so in one line instead of a Java trace", "[cli]") {
  const RigResult r = run_rig("spy", "env -u DISPLAY -u WAYLAND_DISPLAY");
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("no display") != std::string::npos);
  CHECK(r.err.find("xvfb-run") != std::string::npos);
  CHECK(r.err.find("Exception") == std::string::npos);
  const RigResult host = run_rig("spy --pid " + std::to_string(::getpid()));
  CHECK(host.exit_code == 2);
  CHECK(host.err.find("runs on this host's network") != std::string::npos);
}
