// Unit tests of the sweep's campaign report (campaign/sweep_report.h) on synthetic runs: the
// envelopes' percentiles (numpy's linear rule) and their n where short traces end, the controlled
// rate and its Wilson interval, escaping of labels in every file, byte-identical output, and the
// refusals (mixed dt_s) and write errors.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "core/proportion.h"
#include "campaign/sweep.h"
#include "campaign/sweep_report.h"
#include "tests/support/scratch.h"

using namespace nimble::launcher;
using namespace nimble::campaign;
namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

constexpr double kDeg = 180.0 / M_PI;

/// A run of `set` with `samples` grid samples of step `dt_s`: p = p0, v = v0, phi = phi0 [rad] at
/// every time.
SweepRun make_run(std::size_t set, uint64_t seed, bool controlled, double dt_s, std::size_t samples, double p0,
                  double v0, double phi0) {
  SweepRun r;
  r.set = set;
  r.seed = seed;
  r.controlled = controlled;
  r.exit_code = controlled ? 0 : 1;
  if (samples > 0) r.trace.dt_s = dt_s;
  r.trace.p.assign(samples, p0);
  r.trace.v.assign(samples, v0);
  r.trace.phi.assign(samples, phi0);
  return r;
}

SweepResult with_sets(const std::vector<std::string>& labels) {
  SweepResult r;
  r.scenario = "synthetic";
  r.clock = "inprocess";
  for (const auto& l : labels) r.sets.push_back(ParameterSet{l, {}});
  return r;
}

/// A fresh, empty directory for one test.
fs::path fresh_dir(const std::string& name) {
  const fs::path d = nimble::test::scratch_path("sweep_report_" + name);
  fs::remove_all(d);
  return d;
}

std::string slurp(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  REQUIRE(in);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The rows of a CSV text, fields unquoted ("" inside quotes is one quote).
std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows(1, std::vector<std::string>(1));
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        rows.back().back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        rows.back().back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      rows.back().emplace_back();
    } else if (c == '\n') {
      rows.emplace_back(1);
    } else {
      rows.back().back() += c;
    }
  }
  if (rows.back().size() == 1 && rows.back()[0].empty()) rows.pop_back();
  return rows;
}

/// The CSV rows of one set and quantity (columns set,label,quantity,unit,t_s,n,p5,p50,p95).
std::vector<std::vector<std::string>> rows_of(const std::vector<std::vector<std::string>>& rows, int set,
                                              const std::string& quantity) {
  std::vector<std::vector<std::string>> out;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    if (rows[i][0] == std::to_string(set) && rows[i][2] == quantity) out.push_back(rows[i]);
  }
  return out;
}

double num(const std::string& s) { return std::strtod(s.c_str(), nullptr); }

}  // namespace

TEST_CASE("envelopes give numpy's linear percentiles across seeds, phi in degrees", "[sweep_report]") {
  SweepResult r = with_sets({"gain=1"});
  // 21 runs: p = k 0.1 (k = 0..20), v = -k, phi = k 0.01 rad at every one of 4 times.
  for (int k = 0; k <= 20; ++k) r.runs.push_back(make_run(0, 1 + k, true, 0.01, 4, k * 0.1, -k, k * 0.01));
  const auto sets = sweep_report_sets(r);
  REQUIRE(sets.size() == 1);
  const SetReport& s = sets[0];
  CHECK(s.runs == 21);
  CHECK(s.traces == 21);
  CHECK(s.dt_s == 0.01);
  REQUIRE(s.p.t_s.size() == 4);
  for (std::size_t k = 0; k < 4; ++k) {
    CHECK(s.p.t_s[k] == static_cast<double>(k) * 0.01);
    CHECK(s.p.n[k] == 21);
    // Sorted 0, 0.1, ..., 2.0: p5 at position 1, p50 at 10, p95 at 19.
    CHECK(s.p.p5[k] == Approx(0.1));
    CHECK(s.p.p50[k] == Approx(1.0));
    CHECK(s.p.p95[k] == Approx(1.9));
    CHECK(s.v.p5[k] == Approx(-19.0));
    CHECK(s.v.p50[k] == Approx(-10.0));
    CHECK(s.v.p95[k] == Approx(-1.0));
    CHECK(s.phi_deg.p50[k] == Approx(0.1 * kDeg));
    CHECK(s.phi_deg.p95[k] == Approx(0.19 * kDeg));
  }

  // Between order statistics: 10 runs with p = 0..9 give numpy.percentile's 0.45, 4.5 and 8.55.
  SweepResult ten = with_sets({"gain=2"});
  for (int k = 9; k >= 0; --k) ten.runs.push_back(make_run(0, 10 - k, false, 0.02, 2, k, 0.0, 0.0));
  const SetReport t = sweep_report_sets(ten)[0];
  CHECK(t.p.p5[1] == Approx(0.45));
  CHECK(t.p.p50[1] == Approx(4.5));
  CHECK(t.p.p95[1] == Approx(8.55));
  CHECK(t.p.t_s[1] == 0.02);

  // The same figures in envelopes.csv, with numbers that read back exactly.
  const fs::path dir = fresh_dir("percentiles");
  write_sweep_report(r, dir.string());
  const auto rows = parse_csv(slurp(dir / "envelopes.csv"));
  REQUIRE(rows.size() == 1 + 3 * 4);
  CHECK(rows[0] == std::vector<std::string>{"set", "label", "quantity", "unit", "t_s", "n", "p5", "p50", "p95"});
  const auto p = rows_of(rows, 1, "p"), phi = rows_of(rows, 1, "phi");
  REQUIRE(p.size() == 4);
  REQUIRE(phi.size() == 4);
  for (std::size_t k = 0; k < 4; ++k) {
    CHECK(p[k][1] == "gain=1");
    CHECK(p[k][3] == "rad/s");
    CHECK(num(p[k][4]) == s.p.t_s[k]);
    CHECK(p[k][5] == "21");
    CHECK(num(p[k][6]) == s.p.p5[k]);
    CHECK(num(p[k][7]) == s.p.p50[k]);
    CHECK(num(p[k][8]) == s.p.p95[k]);
    CHECK(phi[k][3] == "deg");
    CHECK(num(phi[k][7]) == s.phi_deg.p50[k]);
  }
  CHECK(p[0][4] == "0");
  CHECK(p[1][4] == "0.01");
  fs::remove_all(dir);
}

TEST_CASE("n drops where short traces end and empty traces count only in the rate", "[sweep_report]") {
  SweepResult r = with_sets({"delay=0", "delay=0.01"});
  r.runs.push_back(make_run(0, 1, true, 0.1, 5, 1.0, 10.0, 0.1));
  r.runs.push_back(make_run(0, 2, true, 0.1, 3, 3.0, 30.0, 0.3));
  r.runs.push_back(make_run(0, 3, false, 0.1, 0, 0.0, 0.0, 0.0));  // failed before its first sample
  r.runs.push_back(make_run(1, 1, true, 0.1, 2, 0.0, 0.0, 0.0));
  const auto sets = sweep_report_sets(r);
  const SetReport& s = sets[0];
  CHECK(s.runs == 3);
  CHECK(s.traces == 2);
  CHECK(s.controlled == 2);
  REQUIRE(s.p.n == std::vector<int>{2, 2, 2, 1, 1});
  CHECK(s.p.p50[0] == Approx(2.0));
  CHECK(s.p.p5[0] == Approx(1.1));
  CHECK(s.p.p95[0] == Approx(2.9));
  CHECK(s.p.p50[4] == 1.0);
  CHECK(s.p.p5[4] == 1.0);
  CHECK(s.v.p95[4] == 10.0);
  CHECK(s.p.t_s.back() == Approx(0.4));
  CHECK(sets[1].p.n == std::vector<int>{1, 1});

  // A trace whose p is longer than its phi counts up to the shorter.
  SweepResult uneven = with_sets({"x=1"});
  uneven.runs.push_back(make_run(0, 1, true, 0.1, 4, 1.0, 1.0, 1.0));
  uneven.runs[0].trace.phi.resize(2);
  CHECK(sweep_report_sets(uneven)[0].v.n == std::vector<int>{1, 1});

  const fs::path dir = fresh_dir("short");
  write_sweep_report(r, dir.string());
  const auto rows = parse_csv(slurp(dir / "envelopes.csv"));
  const auto v = rows_of(rows, 1, "v");
  REQUIRE(v.size() == 5);
  CHECK(v[2][5] == "2");
  CHECK(v[3][5] == "1");
  CHECK(num(v[4][7]) == 10.0);
  CHECK(rows_of(rows, 2, "phi").size() == 2);
  const Json j = Json::parse(slurp(dir / "report.json"));
  CHECK(j["sets"][0]["envelopes"]["p"]["n"] == Json::array({2, 2, 2, 1, 1}));
  CHECK(j["sets"][0]["traces"] == 2);
  fs::remove_all(dir);
}

TEST_CASE("controlled rate with its 95 % Wilson interval", "[sweep_report]") {
  SweepResult r = with_sets({"gust=on", "gust=off"});
  for (int k = 0; k < 20; ++k) r.runs.push_back(make_run(0, 1 + k, k < 17, 0.05, 3, 0.0, 0.0, 0.0));
  for (int k = 0; k < 8; ++k) r.runs.push_back(make_run(1, 1 + k, true, 0.05, 3, 0.0, 0.0, 0.0));
  const auto sets = sweep_report_sets(r);
  const nimble::Proportion w17 = nimble::wilson(17, 20), w8 = nimble::wilson(8, 8);
  CHECK(sets[0].controlled == 17);
  CHECK(sets[0].rate.p == 0.85);
  CHECK(sets[0].rate.lo == w17.lo);
  CHECK(sets[0].rate.hi == w17.hi);
  // Independently: the Wilson score interval of 17/20 at z 1.96 is [0.6396, 0.9476].
  CHECK(sets[0].rate.lo == Approx(0.6396).margin(1e-3));
  CHECK(sets[0].rate.hi == Approx(0.9476).margin(1e-3));
  CHECK(sets[1].rate.p == 1.0);
  CHECK(sets[1].rate.hi == 1.0);
  CHECK(sets[1].rate.lo == w8.lo);
  CHECK(sets[1].rate.lo < 1.0);

  const fs::path dir = fresh_dir("wilson");
  write_sweep_report(r, dir.string());
  const Json j = Json::parse(slurp(dir / "report.json"));
  REQUIRE(j["sets"].size() == 2);
  const Json& s0 = j["sets"][0];
  CHECK(s0["set"] == 1);
  CHECK(s0["label"] == "gust=on");
  CHECK(s0["runs"] == 20);
  CHECK(s0["controlled"] == 17);
  CHECK(s0["controlled_rate"].get<double>() == 0.85);
  CHECK(s0["wilson_lo"].get<double>() == w17.lo);
  CHECK(s0["wilson_hi"].get<double>() == w17.hi);
  CHECK(s0["dt_s"].get<double>() == 0.05);
  for (const char* q : {"p", "v", "phi"}) {
    INFO(q);
    for (const char* a : {"t_s", "n", "p5", "p50", "p95"}) CHECK(s0["envelopes"][q][a].size() == 3);
  }
  CHECK(s0["envelopes"]["phi"]["unit"] == "deg");
  CHECK(j["sets"][1]["wilson_lo"].get<double>() == w8.lo);

  const std::string html = slurp(dir / "index.html");
  CHECK(html.find("85.0 %") != std::string::npos);
  CHECK(html.find("64.0-94.8 %") != std::string::npos);
  const std::string svg = slurp(dir / "set-1.svg");
  CHECK(svg.find("controlled 17/20") != std::string::npos);
  CHECK(svg.find("85.0 %") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("a nasty label is escaped in every file", "[sweep_report]") {
  const std::string nasty = "gain=<1> & \"x\", 'y'";
  SweepResult r = with_sets({nasty});
  r.runs.push_back(make_run(0, 1, true, 0.1, 3, 1.0, 2.0, 0.1));
  const fs::path dir = fresh_dir("escape");
  write_sweep_report(r, dir.string());

  const std::string csv = slurp(dir / "envelopes.csv");
  CHECK(csv.find("\"gain=<1> & \"\"x\"\", 'y'\"") != std::string::npos);
  const auto rows = parse_csv(csv);
  REQUIRE(rows.size() == 1 + 9);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    CHECK(rows[i].size() == 9);
    CHECK(rows[i][1] == nasty);
  }
  CHECK(Json::parse(slurp(dir / "report.json"))["sets"][0]["label"] == nasty);
  const std::string escaped = "gain=&lt;1&gt; &amp; &quot;x&quot;, &#39;y&#39;";
  for (const char* file : {"set-1.svg", "index.html"}) {
    INFO(file);
    const std::string text = slurp(dir / file);
    CHECK(text.find(escaped) != std::string::npos);
    CHECK(text.find("<1>") == std::string::npos);
    CHECK(text.find("& \"") == std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("the files: names, SVG panels, a self-contained index", "[sweep_report]") {
  SweepResult r = with_sets({"a=1", "a=2"});
  for (int k = 0; k < 5; ++k) {
    r.runs.push_back(make_run(0, 1 + k, true, 0.01, 50, 0.1 * k, -0.2 * k, 0.01 * k));
    r.runs.push_back(make_run(1, 1 + k, k % 2 == 0, 0.01, 40, 0.3 * k, 0.1 * k, -0.02 * k));
  }
  const fs::path dir = fresh_dir("files") / "nested";
  write_sweep_report(r, dir.string());
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{"envelopes.csv", "index.html", "report.json", "set-1.svg", "set-2.svg"});

  const std::string svg = slurp(dir / "set-2.svg");
  CHECK(svg.rfind("<?xml", 0) == 0);
  CHECK(svg.find("<svg xmlns=\"http://www.w3.org/2000/svg\"") != std::string::npos);
  CHECK(svg.find("Set 2: a=2") != std::string::npos);
  CHECK(svg.find("roll rate p [rad/s]") != std::string::npos);
  CHECK(svg.find("lateral velocity v [m/s]") != std::string::npos);
  CHECK(svg.find("roll phi [deg]") != std::string::npos);
  CHECK(svg.find("t [s]") != std::string::npos);
  const auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (auto at = svg.find(what); at != std::string::npos; at = svg.find(what, at + 1)) ++n;
    return n;
  };
  CHECK(count("<polygon") == 3);
  CHECK(count("<polyline") == 3);
  CHECK(count("text-anchor=\"end\" font-size=\"11\"") >= 6);  // y tick labels, at least two a panel
  CHECK(svg.find("controlled 3/5 = 60.0 %") != std::string::npos);
  CHECK(svg.size() > 2000);
  CHECK(svg.substr(svg.size() - 7) == "</svg>\n");

  const std::string html = slurp(dir / "index.html");
  CHECK(html.rfind("<!DOCTYPE html>", 0) == 0);
  CHECK(html.find("<img src=\"set-1.svg\"") != std::string::npos);
  CHECK(html.find("<img src=\"set-2.svg\"") != std::string::npos);
  CHECK(html.find("http") == std::string::npos);
  CHECK(html.find("<script") == std::string::npos);
  CHECK(html.find("<link") == std::string::npos);
  fs::remove_all(dir.parent_path());
}

TEST_CASE("a constant quantity gets a few ticks around its value", "[sweep_report]") {
  SweepResult r = with_sets({"still=1"});
  // v 0 and p 1e10 at every time in every run: no spread for the axes to span.
  for (int k = 0; k < 3; ++k) r.runs.push_back(make_run(0, 1 + k, true, 0.5, 5, 1e10, 0.0, 0.0));
  const fs::path dir = fresh_dir("constant");
  write_sweep_report(r, dir.string());
  const std::string svg = slurp(dir / "set-1.svg");
  CHECK(svg.find("font-size=\"11\">-1.0</text>") != std::string::npos);
  CHECK(svg.find("font-size=\"11\">1.0</text>") != std::string::npos);
  CHECK(svg.find("font-size=\"11\">10000000000</text>") != std::string::npos);
  CHECK(svg.find("font-size=\"11\">2.0</text>") != std::string::npos);  // t axis up to 2 s
  CHECK(svg.size() < 20000);
  fs::remove_all(dir);
}

TEST_CASE("the same result gives byte-identical files", "[sweep_report]") {
  SweepResult r = with_sets({"k=1", "k=2", "k=3"});
  for (int k = 0; k < 7; ++k) {
    r.runs.push_back(make_run(0, 1 + k, k != 3, 0.004, 30 + 3 * k, std::sin(k), std::cos(k), 0.1 * std::sin(2 * k)));
    r.runs.push_back(make_run(1, 1 + k, true, 0.02, 10, 1.0 / (k + 1), 0.0, 0.0));
    r.runs.push_back(make_run(2, 1 + k, false, 0.0, 0, 0.0, 0.0, 0.0));
  }
  r.wall_time_s = 1.5;
  r.jobs = 1;
  const fs::path a = fresh_dir("same_a"), b = fresh_dir("same_b");
  write_sweep_report(r, a.string());
  // Another machine: other wall time and job count; the report must not change.
  r.wall_time_s = 97.25;
  r.jobs = 16;
  write_sweep_report(r, b.string());
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(a)) {
    INFO(e.path().filename().string());
    REQUIRE(fs::exists(b / e.path().filename()));
    CHECK(slurp(e.path()) == slurp(b / e.path().filename()));
    ++files;
  }
  CHECK(files == 6);
  CHECK(slurp(a / "report.json").find("97.25") == std::string::npos);
  fs::remove_all(a);
  fs::remove_all(b);
}

TEST_CASE("traces of one set with different dt_s are refused, naming the set", "[sweep_report]") {
  SweepResult r = with_sets({"rate=100", "rate=200"});
  r.runs.push_back(make_run(0, 1, true, 0.01, 3, 0.0, 0.0, 0.0));
  r.runs.push_back(make_run(1, 1, true, 0.005, 3, 0.0, 0.0, 0.0));
  r.runs.push_back(make_run(1, 2, true, 0.01, 3, 0.0, 0.0, 0.0));
  const fs::path dir = fresh_dir("mixed");
  try {
    write_sweep_report(r, dir.string());
    FAIL("mixed dt_s accepted");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("rate=200") != std::string::npos);
    CHECK(what.find("set 2") != std::string::npos);
    CHECK(what.find("dt_s") != std::string::npos);
    CHECK(what.find("rate=100") == std::string::npos);
  }
  CHECK_FALSE(fs::exists(dir));  // nothing written

  // Different steps in different sets are fine.
  r.runs[2].trace.dt_s = 0.005;
  const auto sets = sweep_report_sets(r);
  CHECK(sets[0].dt_s == 0.01);
  CHECK(sets[1].dt_s == 0.005);

  // A trace with samples but no step, and a run of a set that does not exist.
  r.runs[0].trace.dt_s = 0.0;
  CHECK_THROWS_AS(sweep_report_sets(r), std::invalid_argument);
  r.runs[0].trace.dt_s = 0.01;
  r.runs[0].set = 2;
  CHECK_THROWS_AS(sweep_report_sets(r), std::invalid_argument);
}

TEST_CASE("a set without traces still gets its rate, no envelope rows and a figure saying so", "[sweep_report]") {
  SweepResult r = with_sets({"processes=[plant]", "processes=[]"});
  r.runs.push_back(make_run(0, 1, true, 0.1, 2, 0.5, 0.5, 0.5));
  for (int k = 0; k < 4; ++k) r.runs.push_back(make_run(1, 1 + k, k == 0, 0.1, 0, 0.0, 0.0, 0.0));
  const fs::path dir = fresh_dir("empty");
  write_sweep_report(r, dir.string());

  const auto rows = parse_csv(slurp(dir / "envelopes.csv"));
  CHECK(rows.size() == 1 + 3 * 2);
  for (const char* q : {"p", "v", "phi"}) CHECK(rows_of(rows, 2, q).empty());
  const Json j = Json::parse(slurp(dir / "report.json"));
  const Json& s = j["sets"][1];
  CHECK(s["runs"] == 4);
  CHECK(s["controlled"] == 1);
  CHECK(s["controlled_rate"].get<double>() == 0.25);
  CHECK(s["wilson_lo"].get<double>() == nimble::wilson(1, 4).lo);
  CHECK(s["wilson_hi"].get<double>() == nimble::wilson(1, 4).hi);
  CHECK(s["traces"] == 0);
  CHECK(s["dt_s"].is_null());
  CHECK(s["envelopes"]["p"]["t_s"].empty());
  const std::string svg = slurp(dir / "set-2.svg");
  CHECK(svg.find("no trace") != std::string::npos);
  CHECK(svg.find("<polygon") == std::string::npos);
  CHECK(svg.find("controlled 1/4 = 25.0 %") != std::string::npos);
  CHECK(slurp(dir / "set-1.svg").find("no trace") == std::string::npos);

  // A set with no runs at all: rate 0 in [0, 1].
  SweepResult none = with_sets({"x=1"});
  const SetReport n = sweep_report_sets(none)[0];
  CHECK(n.runs == 0);
  CHECK(n.rate.lo == 0.0);
  CHECK(n.rate.hi == 1.0);
  CHECK(n.p.t_s.empty());
  fs::remove_all(dir);
}

TEST_CASE("a directory or file that cannot be written is an error naming it", "[sweep_report]") {
  SweepResult r = with_sets({"a=1"});
  r.runs.push_back(make_run(0, 1, true, 0.1, 2, 0.0, 0.0, 0.0));
  const fs::path base = fresh_dir("unwritable");
  fs::create_directories(base);
  { std::ofstream(base / "plain_file") << "not a directory\n"; }
  // Under a regular file: no directory can be made there, whoever runs the test.
  const std::string under_file = (base / "plain_file" / "report").string();
  try {
    write_sweep_report(r, under_file);
    FAIL("wrote under a regular file");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find(under_file) != std::string::npos);
  }
  CHECK_THROWS_AS(write_sweep_report(r, (base / "plain_file").string()), std::runtime_error);

  // The directory exists but one of the files is taken by a directory.
  const fs::path dir = base / "taken";
  fs::create_directories(dir / "report.json");
  try {
    write_sweep_report(r, dir.string());
    FAIL("wrote over a directory");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find((dir / "report.json").string()) != std::string::npos);
  }
  fs::remove_all(base);
}
