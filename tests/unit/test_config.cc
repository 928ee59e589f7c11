// Unit tests of config validation: every error names the file, the key and the value.

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "core/config.h"
#include "core/json_line.h"
#include "core/model.h"
#include "core/param_table.h"
#include "core/vehicle.h"
#include "tests/support/scratch.h"
#include "tests/support/configs.h"

using namespace nimble;

namespace {

using nimble::test::kConfigs;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// Writes `text` to a fresh file in a per-test temporary directory.
std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = nimble::test::scratch_file("test_config", name);
  std::ofstream(path) << text;
  return path;
}

/// The shipped vehicle file with one line replaced (regex on the whole text).
std::string vehicle_with(const std::string& pattern, const std::string& replacement) {
  const std::string text = read_text(kConfigs + "vehicles/nimble_no_wifi.yaml");
  const std::string edited = std::regex_replace(text, std::regex(pattern), replacement);
  REQUIRE(edited != text);
  return write_temp("vehicle.yaml", edited);
}

std::string model_with(const std::string& pattern, const std::string& replacement) {
  std::string text = read_text(kConfigs + "models/nimble_lateral_set1.yaml");
  // Point at the shipped vehicle by absolute path, since the copy lives elsewhere.
  text = std::regex_replace(text, std::regex("vehicle: \\.\\./vehicles/"), "vehicle: " + kConfigs + "vehicles/");
  const std::string edited = std::regex_replace(text, std::regex(pattern), replacement);
  REQUIRE(edited != text);
  return write_temp("model.yaml", edited);
}

/// Runs `load`, requires a ConfigError, checks it names file, key and value.
template <typename Fn>
void expect_error(Fn load, const std::string& file, const std::string& key, const std::string& value,
                  const std::string& problem_part) {
  try {
    load();
    FAIL("expected a ConfigError for key " << key);
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    INFO(what);
    CHECK(e.file() == file);
    CHECK(e.key() == key);
    CHECK(e.value() == value);
    CHECK(what.find(file) != std::string::npos);
    if (!key.empty()) CHECK(what.find("'" + key + "'") != std::string::npos);
    if (!value.empty()) CHECK(what.find("'" + value + "'") != std::string::npos);
    CHECK(what.find(problem_part) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("shipped vehicle files load with the thesis values", "[config]") {
  const Vehicle v = load_vehicle(kConfigs + "vehicles/nimble_no_wifi.yaml");
  CHECK(v.mass_kg == Approx(28.76e-3));
  CHECK(v.Ixz_kgm2 == Approx(-8.81e-6));
  CHECK(v.flap_frequency_radps() == Approx(106.8).epsilon(0.001));
  const Vehicle w = load_vehicle(kConfigs + "vehicles/nimble_wifi.yaml");
  CHECK(w.mass_kg == Approx(29.47e-3));
  CHECK(w.Ixx_kgm2 == Approx(9.76e-5));
  CHECK(w.Izz_kgm2 == Approx(3.34e-5));
  // The physical bounds of recorded data (data_bounds; sources in the files); a file without the
  // section (or a key) has the defaults, which are the shipped files' values.
  // Both files write every key of the table (at the default, checked below).
  for (const char* file : {"vehicles/nimble_no_wifi.yaml", "vehicles/nimble_wifi.yaml"}) {
    const std::string text = read_text(kConfigs + file);
    for (const auto& p : data_bounds_params()) {
      INFO(file << ": data_bounds." << p.key);
      CHECK(text.find("\n  " + p.key + ": ") != std::string::npos);
    }
  }
  std::string text = read_text(kConfigs + "vehicles/nimble_no_wifi.yaml");
  const std::size_t section = text.find("# Physical bounds of recorded flight data");
  REQUIRE(section != std::string::npos);
  const Vehicle bare = load_vehicle(write_temp("bare_vehicle.yaml", text.substr(0, section)));
  for (const Vehicle* x : {&v, &w, &bare}) {
    CHECK(x->data_bounds.rate_max_radps == 50.0);
    CHECK(x->data_bounds.speed_max_mps == 20.0);
    CHECK(x->data_bounds.angle_max_rad == Approx(M_PI));
    CHECK(x->data_bounds.delta_f_max_radps == 500.0);
    CHECK(x->data_bounds.throttle_max_pct == 100.0);
    CHECK(x->data_bounds.servo_max_rad == Approx(M_PI / 2));
    CHECK(x->data_bounds.specific_force_max_mps2 == 200.0);
  }
}

TEST_CASE("every shipped model file loads", "[config]") {
  for (const auto& entry : std::filesystem::directory_iterator(kConfigs + "models")) {
    INFO(entry.path());
    const DerivativeModel m = load_model(entry.path().string());
    CHECK(std::filesystem::exists(m.vehicle_file));
    CHECK_NOTHROW(build_state_space(m, load_vehicle(m.vehicle_file)));
  }
}

TEST_CASE("vehicle errors name file, key and value", "[config]") {
  SECTION("missing key") {
    const auto f = vehicle_with("mass_kg: 0.02876\n", "");
    expect_error([&] { load_vehicle(f); }, f, "mass_kg", "", "missing required key");
  }
  SECTION("unknown key") {
    const auto f = vehicle_with("mass_kg: 0.02876", "mass_kg: 0.02876\nmas_kg: 0.03");
    expect_error([&] { load_vehicle(f); }, f, "mas_kg", "0.03", "unknown key");
  }
  SECTION("unknown nested key") {
    const auto f = vehicle_with("  Ixz: -8.81e-6", "  Ixz: -8.81e-6\n  Ixy: 1e-6");
    expect_error([&] { load_vehicle(f); }, f, "inertia_kgm2.Ixy", "1e-6", "unknown key");
  }
  SECTION("non-numeric value") {
    const auto f = vehicle_with("mass_kg: 0.02876", "mass_kg: heavy");
    expect_error([&] { load_vehicle(f); }, f, "mass_kg", "heavy", "must be a number");
  }
  SECTION("number followed by a unit") {
    const auto f = vehicle_with("mass_kg: 0.02876", "mass_kg: 28.76 g");
    expect_error([&] { load_vehicle(f); }, f, "mass_kg", "28.76 g", "must be a number");
  }
  SECTION("non-finite value") {
    const auto f = vehicle_with("mass_kg: 0.02876", "mass_kg: .nan");
    expect_error([&] { load_vehicle(f); }, f, "mass_kg", ".nan", "finite");
  }
  SECTION("non-positive mass") {
    const auto f = vehicle_with("mass_kg: 0.02876", "mass_kg: -0.029");
    expect_error([&] { load_vehicle(f); }, f, "mass_kg", "-0.029", "must be > 0");
  }
  SECTION("zero mass") {
    const auto f = vehicle_with("mass_kg: 0.02876", "mass_kg: 0");
    expect_error([&] { load_vehicle(f); }, f, "mass_kg", "0", "must be > 0");
  }
  SECTION("non-positive inertia") {
    const auto f = vehicle_with("Izz: 3.32e-5", "Izz: -3.32e-5");
    expect_error([&] { load_vehicle(f); }, f, "inertia_kgm2.Izz", "-3.32e-5", "must be > 0");
  }
  SECTION("a data bound not > 0, or unknown") {
    const auto g = vehicle_with("speed_max_mps: 20.0", "speed_max_mps: 0");
    expect_error([&] { load_vehicle(g); }, g, "data_bounds.speed_max_mps", "0", "must be > 0");
    const auto u = vehicle_with("  speed_max_mps: 20.0", "  speed_max_mps: 20.0\n  altitude_max_m: 7");
    expect_error([&] { load_vehicle(u); }, u, "data_bounds.altitude_max_m", "7", "unknown key");
  }
  SECTION("Ixx*Izz - Ixz^2 <= 0") {
    const auto f = vehicle_with("Ixz: -8.81e-6", "Ixz: -6.0e-5");
    expect_error([&] { load_vehicle(f); }, f, "inertia_kgm2.Ixz", "-6.0e-5", "Ixx*Izz - Ixz^2");
  }
  SECTION("missing file") {
    const std::string f = "/nonexistent/vehicle.yaml";
    expect_error([&] { load_vehicle(f); }, f, "", "", "file not found");
  }
  SECTION("invalid YAML gives the line") {
    const auto f = write_temp("broken.yaml", "name: x\nmass_kg: [1, 2\n");
    try {
      load_vehicle(f);
      FAIL("expected a ConfigError");
    } catch (const ConfigError& e) {
      CHECK(std::string(e.what()).find("not valid YAML") != std::string::npos);
      CHECK(e.line() > 0);
    }
  }
}

TEST_CASE("model errors name file, key and value", "[config]") {
  SECTION("missing derivative") {
    const auto f = model_with("  Lv: -3.74e-04 .*\n", "");
    expect_error([&] { load_model(f); }, f, "derivatives.Lv", "", "missing required key");
  }
  SECTION("derivative the structure does not have") {
    const auto f = model_with("  Lp: -2.43e-04", "  Lp: -2.43e-04\n  Nr: 1.0e-4");
    expect_error([&] { load_model(f); }, f, "derivatives.Nr", "1.0e-4", "unknown key");
  }
  SECTION("non-numeric derivative") {
    const auto f = model_with("Yv: -5.61e-02", "Yv: -5.61e-02x");
    expect_error([&] { load_model(f); }, f, "derivatives.Yv", "-5.61e-02x", "must be a number");
  }
  SECTION("unknown structure") {
    const auto f = model_with("structure: lateral3", "structure: lateral5");
    expect_error([&] { load_model(f); }, f, "structure", "lateral5", "must be one of");
  }
  SECTION("unknown input") {
    const auto f = model_with("inputs: \\[delta_f, delta_t\\]", "inputs: [delta_f, delta_x]");
    expect_error([&] { load_model(f); }, f, "inputs", "[delta_f, delta_x]", "unknown input 'delta_x'");
  }
  SECTION("missing trim value") {
    const auto f = model_with("  w0_mps: -0.30\n", "");
    expect_error([&] { load_model(f); }, f, "trim.w0_mps", "", "missing required key");
  }
  SECTION("misspelt top-level key") {
    const auto f = model_with("source:", "sauce:");
    expect_error([&] { load_model(f); }, f, "source", "", "missing required key");
  }
}

TEST_CASE("json_line: keys in written order, escapes, non-finite numbers as null, doubles that read back exactly",
          "[json]") {
  const double third = 1.0 / 3.0;
  nimble::OrderedJson j;
  j["zeta"] = third;
  j["alpha"] = -7;
  j["text"] = "quote \" backslash \\ newline \n tab \t bell \a";
  j["nan"] = std::nan("");
  j["inf"] = HUGE_VAL;
  j["flag"] = true;
  j["list"] = std::vector<double>{1.5, -0.0, 1e-300};
  j["nested"] = {{"empty", nimble::OrderedJson::array()}, {"none", nullptr}};
  j["bad_utf8"] = "ok \xff\xfe end";
  j["complex"] = nimble::complex_json({1.5, -2.0});
  const std::string s = nimble::json_line(j);
  INFO(s);
  CHECK(s.find("\"zeta\"") < s.find("\"alpha\""));  // written order, not sorted
  CHECK(s.find("\\\"") != std::string::npos);
  CHECK(s.find("\\n") != std::string::npos);
  CHECK(s.find("\\u0007") != std::string::npos);
  CHECK(s.find("\"nan\":null") != std::string::npos);
  CHECK(s.find("\"inf\":null") != std::string::npos);
  CHECK(s.find('\n') == std::string::npos);  // one line
  // It parses, and the double reads back to the same bits.
  const YAML::Node n = YAML::Load(s);
  CHECK(n["zeta"].as<double>() == third);
  CHECK(n["list"][2].as<double>() == 1e-300);
  CHECK(n["nested"]["empty"].size() == 0);
  CHECK(n["text"].as<std::string>() == "quote \" backslash \\ newline \n tab \t bell \a");
  CHECK(n["bad_utf8"].as<std::string>().find("\xef\xbf\xbd") != std::string::npos);  // U+FFFD
  CHECK(n["complex"][1].as<double>() == -2.0);
  CHECK(nimble::json_quote("a\"b") == "\"a\\\"b\"");
}

TEST_CASE("a key that is not a plain name is a ConfigError naming its line", "[config]") {
  // Found by fuzz_model_yaml: `[a, b]: 1` in a model file ended `rig model` with yaml-cpp's
  // bad conversion (ConfigMap::keys), not with the loader's error.
  for (const char* text : {"name: x\n[a, b]: 1\n", "name: x\neffects:\n  ? {a: 1}\n  : 2\n", "name: x\n? \n: 3\n"}) {
    INFO(text);
    try {
      (void)ConfigMap::load_string(text, "model.yaml");
      FAIL("no ConfigError");
    } catch (const ConfigError& e) {
      CHECK(std::string(e.what()).find("a key must be a plain name") != std::string::npos);
      CHECK(std::string(e.what()).find("model.yaml") != std::string::npos);
    }
  }
  ConfigMap plain = ConfigMap::load_string("name: x\n1: 2\n", "model.yaml");
  CHECK(plain.keys().size() == 2);
}
