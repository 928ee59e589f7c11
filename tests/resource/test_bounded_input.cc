// Inputs bounded before they are read (core/input_file.h, core/yaml_input.h): /dev/zero and a
// FIFO given to every command that takes a file are refused at once, exit 2, naming the path (a
// FIFO would hang a reader that opens it, /dev/zero would be read until memory runs out); a YAML
// alias bomb is refused naming the file and line; a base: cycle names every file of it;
// /proc/self/mem as a scenario is named, not basic_filebuf::underflow. Every command runs under
// `timeout`, so a reader that waits or reads without end fails the case instead of the suite.

#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "tests/support/run_rig.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;
using nimble::test::run_rig;

namespace {

const std::string kSource = RIG_SOURCE_DIR;
const std::string kModel = kSource + "/rig_configs/models/nimble_lateral_set1.yaml";
const std::string kScenario = kSource + "/rig_configs/hover.yaml";

/// A FIFO in the scratch folder, with no writer: opening it for reading blocks.
std::string fifo() {
  const std::string path = nimble::test::scratch_file("bounded_input", "pipe.fifo");
  if (!fs::exists(path)) REQUIRE(::mkfifo(path.c_str(), 0600) == 0);
  return path;
}

std::string write(const std::string& name, const std::string& text) {
  const std::string path = nimble::test::scratch_file("bounded_input", name);
  std::ofstream(path) << text;
  return path;
}

/// Runs `rig ARGS` (within 20 s) and checks it is refused: exit 2, the path named with `problem`.
void refused(const std::string& args, const std::string& path, const std::string& problem) {
  INFO("rig " << args);
  const auto r = run_rig(args + " </dev/null", "timeout 20");
  INFO(r.err);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find(path) != std::string::npos);
  CHECK(r.err.find(problem) != std::string::npos);
}

/// Every command that takes a file, with `bad` in the place of one of its files.
std::vector<std::string> commands_with(const std::string& bad) {
  const std::string out = nimble::test::scratch_file("bounded_input", "out");
  return {
      "run " + bad + " --clock inprocess --no-progress",
      "run " + kScenario + " --clock inprocess --no-progress --set model=" + bad,
      "sweep " + bad + " --seeds 1-1",
      "identify " + bad,
      "validate " + kModel + " " + bad,
      "validate " + bad + " " + kSource + "/rig_configs/hover.yaml",
      "discrepancy " + bad + " --model " + kModel,
      "discrepancy " + kSource + "/rig_configs/hover.yaml --model " + bad,
      "discrepancy --power --scenario " + bad + " --model " + kModel + " --effect lateral_inflow=-0.01 --flights 1",
      "export " + bad + " --csv " + out + ".csv",
      "export " + bad + " --format mcap --out " + out + ".mcap",
      "view " + bad + " --exit-when-done --foxglove 127.0.0.1:0",
      "model " + bad,
      "model " + kModel + " --vehicle " + bad,
      "loop " + bad,
      "turbulence " + bad,
      "turbulence-response " + kSource + "/rig_configs/hover_turbulence.yaml " + bad,
      "reproduce thesis --campaign " + bad + " --seeds 1",
  };
}

}  // namespace

TEST_CASE("/dev/zero into every command that takes a file is refused at once, naming it", "[resource]") {
  for (const std::string& args : commands_with("/dev/zero")) {
    refused(args, "/dev/zero", "is not a regular file (a character device)");
  }
}

TEST_CASE("a FIFO into every command that takes a file is refused, not waited on", "[resource]") {
  const std::string pipe = fifo();
  for (const std::string& args : commands_with(pipe)) refused(args, pipe, "is not a regular file (a FIFO)");
}

TEST_CASE("a file above the bound of its kind is refused before it is read, naming the size and the bound",
          "[resource]") {
  // Sparse files: their size is what the bound looks at, and nothing of them is read.
  const auto sparse = [](const std::string& name, std::uintmax_t bytes) {
    const std::string path = nimble::test::scratch_file("bounded_input", name);
    std::ofstream{path};
    fs::resize_file(path, bytes);
    return path;
  };
  const std::string log = sparse("huge.lcmlog", 2'100'000'000);
  refused("identify " + log, log, "is 2.1 GB, above the 2.0 GB bound for an LCM log");
  refused("export " + log + " --format mcap --out " + log + ".mcap", log, "above the 2.0 GB bound for an LCM log");
  const std::string csv = sparse("huge.csv", 600'000'000);
  refused("identify " + csv, csv, "is 600.0 MB, above the 512.0 MB bound for a flight record");
  const std::string scenario = sparse("huge.yaml", 5'000'000);
  refused("run " + scenario + " --clock inprocess --no-progress", scenario,
          "is 5.0 MB, above the 4.0 MB bound for a configuration file");
  for (const std::string& f : {log, csv, scenario}) fs::remove(f);
  CHECK_FALSE(fs::exists(log + ".mcap"));
}

TEST_CASE("a FIFO as a base: file is refused, naming it and the key", "[resource]") {
  const std::string pipe = fifo();
  const std::string scenario = write("fifo_base.yaml", "base: " + pipe + "\nduration_s: 1\n");
  refused("run " + scenario + " --clock inprocess --no-progress", pipe, "is not a regular file (a FIFO)");
  const auto r = run_rig("run " + scenario + " --clock inprocess --no-progress </dev/null", "timeout 20");
  CHECK(r.err.find("key 'base'") != std::string::npos);
}

TEST_CASE("a YAML alias bomb is refused at once, naming the file and line", "[resource]") {
  // Ten levels of nine aliases each: 9^10 scalars as expanded.
  std::string text = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 10; ++i) {
    const std::string prev = "*a" + std::to_string(i - 1);
    std::string list;
    for (int k = 0; k < 9; ++k) list += (k ? ", " : "") + prev;
    text += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [" + list + "]\n";
  }
  const std::string bomb = write("bomb.yaml", text);
  refused("run " + bomb + " --clock inprocess --no-progress",
          bomb + ":6:", "YAML aliases expand to more than 100000 nodes");
  refused("model " + bomb, bomb + ":6:", "YAML aliases expand to more than 100000 nodes");
  // As a base file, and through --set.
  const std::string scenario = write("bomb_base.yaml", "base: " + bomb + "\n");
  refused("run " + scenario + " --clock inprocess --no-progress", bomb, "YAML aliases expand");
  std::string inline_bomb = "[&b0 [x, x, x, x, x, x, x, x, x]";
  for (int i = 1; i < 10; ++i) {
    inline_bomb += ", &b" + std::to_string(i) + " [";
    for (int k = 0; k < 9; ++k) inline_bomb += std::string(k ? ", " : "") + "*b" + std::to_string(i - 1);
    inline_bomb += "]";
  }
  inline_bomb += "]";
  refused("run " + kScenario + " --clock inprocess --no-progress --set 'plant.x=" + inline_bomb + "'", "--set",
          "YAML aliases expand");
}

TEST_CASE("a YAML alias inside its own anchor's node is refused as a cycle, not walked for ever", "[resource]") {
  // yaml-cpp builds it as a node that contains itself: every walk of it overflowed the stack.
  const std::string scenario = write("self_alias.yaml", "base: hover.yaml\nplant: &p\n  x: [1, *p]\n");
  refused("run " + scenario + " --clock inprocess --no-progress", scenario + ":3:", "(a cycle)");
  refused("model " + scenario, scenario + ":3:", "a YAML alias inside the node its anchor names");
}

TEST_CASE("a base: cycle is refused naming every file of it", "[resource]") {
  const std::string a = nimble::test::scratch_file("bounded_input", "cycle_a.yaml");
  const std::string b = nimble::test::scratch_file("bounded_input", "cycle_b.yaml");
  const std::string c = nimble::test::scratch_file("bounded_input", "cycle_c.yaml");
  std::ofstream(a) << "base: cycle_b.yaml\nduration_s: 1\n";
  std::ofstream(b) << "base: cycle_c.yaml\n";
  std::ofstream(c) << "plant:\n  base: cycle_a.yaml\n";
  refused("run " + a + " --clock inprocess --no-progress", "base files form a cycle",
          a + " -> " + b + " -> " + c + " -> " + a);
}

TEST_CASE("a campaign manifest that is a FIFO or /dev/zero is refused naming it", "[resource]") {
  const std::string pipe = fifo();
  for (const std::string& bad : {pipe, std::string("/dev/zero")}) {
    const std::string dir = nimble::test::scratch_dir("bounded_input_campaign");
    fs::create_symlink(bad, fs::path(dir) / "campaign.json");
    const std::string manifest = dir + "/campaign.json";
    const std::string problem = bad == pipe ? "(a FIFO)" : "(a character device)";
    refused("sweep --resume " + dir, manifest, "is not a regular file " + problem);
    refused("sweep collect " + dir, manifest, "is not a regular file " + problem);
  }
}

TEST_CASE("/proc/self/mem and a directory as a scenario are refused naming the file", "[resource]") {
  const auto r = run_rig("run /proc/self/mem --clock inprocess --no-progress </dev/null", "timeout 20");
  INFO(r.err);
  CHECK(r.exit_code == 2);
  CHECK(r.err.find("/proc/self/mem") != std::string::npos);
  CHECK(r.err.find("cannot be read") != std::string::npos);
  CHECK(r.err.find("underflow") == std::string::npos);
  const std::string dir = nimble::test::scratch_dir("bounded_input_dir");
  refused("run " + dir + " --clock inprocess --no-progress", dir, "is a directory, not a file");
  refused("identify " + dir, dir, "is a directory, not a file");
}
