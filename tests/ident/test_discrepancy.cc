// Tests of the discrepancy workflow (discrepancy/discrepancy.h) on records with a hidden effect
// from an in-test generator independent of the plant code (discrepancy_generator.h).

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include <unistd.h>

#include <catch2/catch.hpp>

#include "core/config.h"
#include "discrepancy_generator.h"
#include "discrepancy/discrepancy.h"
#include "effects/registry.h"
#include "discrepancy/discrepancy_location.h"
#include "ident/model_writer.h"
#include "tests/support/scratch.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

DiscrepancyResult run(const std::set<std::string>& effects, std::uint64_t seed, double scale = 1.0) {
  ident::test::HiddenEffects h;
  h.on = effects;
  h.scale = scale;
  ident::test::draw_magnitudes(h, seed);
  ident::test::GeneratorOptions o;
  o.seed = seed;
  const FlightData d = ident::test::generate_flight(ident::test::set1().model, ident::test::set1().vehicle, h, o);
  DiscrepancyResult r = find_discrepancy(d, ident::test::set1().model, ident::test::set1().vehicle, {});
  // Where an effect is named, some band shows the gap shrinking by at least 20 %, or each
  // effect band says why it cannot.
  if (!r.effects.empty()) {
    INFO("seed " << seed << ": " << r.summary);
    REQUIRE(!r.gap_bands.empty());
    CHECK(r.gap_bands.front().name == "identification band");
    bool shrinks = false, noted = true;
    for (const auto& b : r.gap_bands) {
      shrinks = shrinks || b.after <= 0.8 * b.before;
      if (b.name != "identification band") noted = noted && !b.note.empty();
    }
    CHECK((shrinks || (noted && r.gap_bands.size() > 1)));
  }
  return r;
}

std::vector<std::string> names(const DiscrepancyResult& r) {
  std::vector<std::string> out;
  for (const auto& e : r.effects) out.push_back(e.name);
  return out;
}

bool named(const DiscrepancyResult& r, const std::string& name) {
  const auto n = names(r);
  return std::find(n.begin(), n.end(), name) != n.end();
}

}  // namespace

// Records with no hidden effect: tests/ident/test_discrepancy_nulls.cc measures the family-wise
// false-alarm rate (names, ambiguous, unexplained) over 240 of them.

TEST_CASE("discrepancy: a hidden kinematic coupling is named, its coefficient is the mass, the held-out gap shrinks",
          "[discrepancy][heavy]") {
  for (std::uint64_t s = 1; s <= 3; ++s) {
    const DiscrepancyResult r = run({"kinematic_coupling"}, s);
    INFO("seed " << s << ": " << r.summary);
    REQUIRE(r.verdict == "effects");
    REQUIRE(named(r, "kinematic_coupling"));
    CHECK(r.effects.size() == 1);
    const NamedEffect& e = r.effects.front();
    const double m = ident::test::set1().vehicle.mass_kg;
    CHECK(std::fabs(e.parameters.at("Y_pw") - m) < 5.0 * e.sigma.at("Y_pw"));
    CHECK(r.gap_after < 0.5 * r.gap_before);
    // The refit Yp comes back to the model's value once the effect is in (Eq 21's bias gone).
    const auto& yp = r.augmented.at("Yp");
    CHECK(std::fabs(yp.value - ident::test::set1().model.at("Yp")) < 4.0 * yp.sigma_coloured + 1e-9);
    CHECK(std::fabs(r.baseline.at("Yp").value - ident::test::set1().model.at("Yp")) >
          std::fabs(yp.value - ident::test::set1().model.at("Yp")));
  }
}

TEST_CASE(
    "discrepancy: a lateral gust alone is named lateral_gust from its signature, a deterministic name in at "
    "most 5 % of 24 records",
    "[discrepancy][null][records]") {
  // A side gust drives v and so correlates the equation error with functions of v in closed
  // loop; the confirmation above the gust band removes most of it (6 of 24 records named
  // lateral_inflow without it). The rate is measured, and must not exceed the null rate bound.
  // The gust itself has no regressor: it is named from the low-frequency excess of the side-force
  // residual, with its size (generator: sigma 0.1 m/s, tau 0.5 s).
  int deterministic = 0, gust = 0;
  for (int s = 1; s <= 24; ++s) {
    const DiscrepancyResult r = run({"lateral_gust"}, static_cast<std::uint64_t>(s));
    INFO("seed " << s << ": " << r.summary);
    for (const auto& e : r.effects) {
      if (e.name != "lateral_gust") {
        ++deterministic;
        break;
      }
    }
    if (!named(r, "lateral_gust")) continue;
    ++gust;
    const NamedEffect& e = *std::find_if(r.effects.begin(), r.effects.end(),
                                         [](const NamedEffect& x) { return x.name == "lateral_gust"; });
    CHECK(e.parameters.at("sigma_mps") > 0.05);
    CHECK(e.parameters.at("sigma_mps") < 0.2);
    CHECK(e.parameters.at("tau_s") > 0.1);
    CHECK(e.parameters.at("tau_s") < 1.5);
    // Random: nothing to refit, the gap stays.
    if (r.effects.size() == 1) CHECK(r.gap_after == Approx(r.gap_before));
  }
  std::printf("discrepancy gust-only records: %d of 24 named a deterministic effect, %d of 24 named lateral_gust\n",
              deterministic, gust);
  CHECK(deterministic <= 1);
  CHECK(gust >= 22);
}

TEST_CASE("discrepancy: a hidden actuator delay (12-40 ms) is named with its delay", "[discrepancy][records]") {
  int hits = 0;
  const int seeds = 8;
  for (int s = 1; s <= seeds; ++s) {
    ident::test::HiddenEffects h;
    h.on = {"actuator_delay"};
    ident::test::draw_magnitudes(h, static_cast<std::uint64_t>(s));
    const DiscrepancyResult r = run({"actuator_delay"}, static_cast<std::uint64_t>(s));
    INFO("seed " << s << " delay " << h.delay_s << ": " << r.summary);
    for (const auto& n : names(r)) CHECK(n == "actuator_delay");
    if (!named(r, "actuator_delay")) continue;
    ++hits;
    // The scan's grid is one sample (1.95 ms); in closed loop the estimate runs a little low.
    CHECK(std::fabs(r.effects.front().parameters.at("delay_s") - h.delay_s) < 0.006);
  }
  std::printf("discrepancy actuator delay: named in %d of %d records\n", hits, seeds);
  CHECK(hits >= 7);
}

TEST_CASE(
    "discrepancy: a command delay before the actuator (12-40 ms) is named from the recorded command, and with "
    "no delay the recorded command names nothing",
    "[discrepancy][records]") {
  // The recorded delta_f is the actuator's output, so the L and Y equations cannot see a delay
  // before the actuator; the actuator equation (delta_f against the recorded command) does.
  // The generator's command path has no latency of its own: command_latency_s 0.
  DiscrepancyOptions opt;
  opt.command_latency_s = 0.0;
  int hits = 0, null_named = 0;
  for (int s = 1; s <= 6; ++s) {
    ident::test::HiddenEffects h;
    h.on = {"command_delay"};
    ident::test::draw_magnitudes(h, static_cast<std::uint64_t>(s));
    ident::test::GeneratorOptions o;
    o.seed = static_cast<std::uint64_t>(s);
    o.record_command = true;
    const DiscrepancyResult r =
        find_discrepancy(ident::test::generate_flight(ident::test::set1().model, ident::test::set1().vehicle, h, o),
                         ident::test::set1().model, ident::test::set1().vehicle, opt);
    INFO("seed " << s << " delay " << h.delay_s << ": " << r.summary);
    for (const auto& n : names(r)) CHECK(n == "actuator_delay");
    if (named(r, "actuator_delay")) {
      ++hits;
      const NamedEffect& e = r.effects.front();
      CHECK(std::fabs(e.parameters.at("delay_s") - h.delay_s) < 0.003);
      CHECK(e.parameters.count("F_cmd_delayed") == 1);
      CHECK(r.gap_after < r.gap_before);
    }
    ident::test::HiddenEffects none;
    const DiscrepancyResult n0 =
        find_discrepancy(ident::test::generate_flight(ident::test::set1().model, ident::test::set1().vehicle, none, o),
                         ident::test::set1().model, ident::test::set1().vehicle, opt);
    INFO("null seed " << s << ": " << n0.summary);
    null_named += !n0.effects.empty();
    // The actuator equation is part of the model when the command is recorded.
    CHECK(std::any_of(n0.gap.begin(), n0.gap.end(), [](const OutputGap& g) { return g.output == "delta_f_dot"; }));
  }
  std::printf("discrepancy command delay: named in %d of 6 records, %d of 6 nulls named anything\n", hits, null_named);
  CHECK(hits == 6);
  CHECK(null_named == 0);
}

TEST_CASE(
    "discrepancy: a hidden lateral inflow is named with the damping sign in two thirds of 24 records and in all "
    "but one of the upper half of its range, nothing else is named",
    "[discrepancy][records]") {
  // Power grows with the size: Y_vv is drawn from [-0.03, -0.01]; the upper half of the range
  // (|Y_vv| >= 0.02) must be named in all its records but one, the whole range in 16 of 24.
  int hits = 0, large = 0, large_hits = 0;
  const int seeds = 24;
  for (int s = 1; s <= seeds; ++s) {
    const DiscrepancyResult r = run({"lateral_inflow"}, static_cast<std::uint64_t>(s));
    ident::test::HiddenEffects h;
    ident::test::draw_magnitudes(h, static_cast<std::uint64_t>(s));
    const bool is_large = h.Y_vv <= -0.02;
    large += is_large;
    INFO("seed " << s << " Y_vv " << h.Y_vv << ": " << r.summary);
    // Nothing else: the library's name, or (where the name is not earned) the inflow's own form
    // found by the open-world search, a v|v| side force.
    for (const auto& e : r.effects) {
      CHECK((e.name == "lateral_inflow" || (e.name == "term" && e.equation == "Y" && e.expression == "v*abs(v)")));
    }
    if (!named(r, "lateral_inflow")) continue;
    ++hits;
    large_hits += is_large;
    const NamedEffect& e = r.effects.front();
    REQUIRE(e.parameters.count("Y_vv") == 1);
    CHECK(e.parameters.at("Y_vv") < 0.0);
    CHECK(r.gap_after < r.gap_before);
  }
  std::printf("discrepancy lateral inflow: named in %d of %d records, %d of the %d with |Y_vv| >= 0.02\n", hits, seeds,
              large_hits, large);
  CHECK(hits >= 16);
  CHECK(large_hits >= large - 1);
}

TEST_CASE("discrepancy: a hidden forward-speed coupling is named with the sign of its gain", "[discrepancy][heavy]") {
  for (std::uint64_t s = 1; s <= 3; ++s) {
    const DiscrepancyResult r = run({"forward_speed_coupling"}, s);
    INFO("seed " << s << ": " << r.summary);
    REQUIRE(r.verdict == "effects");
    REQUIRE(named(r, "forward_speed_coupling"));
    // Lp scales with (1 + k u): L_up = k Lp, negative for k > 0 and Lp < 0.
    const NamedEffect& e = r.effects.front();
    CHECK(e.parameters.at("L_up") < 0.0);
    CHECK(r.gap_after < r.gap_before);
    for (const auto& o : r.gap) CHECK(o.rmse_after <= o.rmse_before);
  }
}

TEST_CASE("discrepancy: a hidden flapping forcing (14-20 Hz) is named at its frequency", "[discrepancy][heavy]") {
  for (std::uint64_t s = 1; s <= 4; ++s) {
    ident::test::HiddenEffects h;
    h.on = {"flapping_forcing"};
    ident::test::draw_magnitudes(h, s);
    const DiscrepancyResult r = run({"flapping_forcing"}, s);
    INFO("seed " << s << " f " << h.flap_hz << ": " << r.summary);
    REQUIRE(names(r) == std::vector<std::string>{"flapping_forcing"});
    const auto& p = r.effects.front().parameters;
    CHECK(std::fabs(p.at("flapping_hz") - h.flap_hz) < 0.05);
    // The roll moment of the first harmonic comes back (generator: A_L sin(2 pi f t + a)).
    CHECK(p.at("L_amp1") == Approx(h.flap_L).epsilon(0.15));
    // The gap where the forcing lives: at its harmonics on the wideband data, not in the
    // identification band (which the 9 Hz low-pass keeps it out of).
    const auto band = std::find_if(r.gap_bands.begin(), r.gap_bands.end(),
                                   [](const BandGap& b) { return b.name == "flapping_forcing harmonic 1"; });
    REQUIRE(band != r.gap_bands.end());
    CHECK(band->wideband);
    CHECK(band->lo_hz < h.flap_hz);
    CHECK(band->hi_hz > h.flap_hz);
    CHECK(band->after < 0.5 * band->before);
    std::printf(
        "flapping forcing %.2f Hz (seed %d): identification band gap %.4g -> %.4g, harmonic 1 band %.2f-%.2f Hz "
        "%.4g -> %.4g\n",
        h.flap_hz, static_cast<int>(s), r.gap_before, r.gap_after, band->lo_hz, band->hi_hz, band->before, band->after);
  }
}

TEST_CASE("discrepancy: a sensor bias is named from the kinematics, and the gap shrinks where it lives",
          "[discrepancy][heavy]") {
  // The data-compatibility stage finds the gyro's bias in phi_dot = p before any aerodynamic term
  // and corrects the record; L and Y then need no constant.
  for (std::uint64_t s = 1; s <= 3; ++s) {
    ident::test::HiddenEffects h;
    h.on = {"sensor_bias"};
    ident::test::draw_magnitudes(h, s);
    ident::test::GeneratorOptions o;
    o.seed = s;
    const DiscrepancyResult r =
        find_discrepancy(ident::test::generate_flight(ident::test::set1().model, ident::test::set1().vehicle, h, o),
                         ident::test::set1().model, ident::test::set1().vehicle, {});
    INFO("seed " << s << " bias " << h.bias_p << ": " << r.summary);
    REQUIRE(r.effects.size() == 1);
    const NamedEffect& e = r.effects.front();
    CHECK(e.name == "sensor_bias");
    CHECK(e.channel == "p");
    CHECK(e.interval[0] <= h.bias_p);
    CHECK(h.bias_p <= e.interval[1]);
    REQUIRE(r.compatibility.size() == 1);
    const CompatibilityResult& c = r.compatibility.front();
    CHECK(c.kinematic_gap_after < 0.5 * c.kinematic_gap_before);
    REQUIRE(c.rmse_uncorrected.count("p_dot"));
    CHECK(r.gap.front().rmse_before < c.rmse_uncorrected.at("p_dot"));
  }
}

TEST_CASE(
    "discrepancy: a nonlinearity outside the candidates is located (unexplained, in the side-force equation) "
    "and, with the open-world search, found as the term v*abs(v) in Y",
    "[discrepancy][records]") {
  // A lateral inflow at three times its drawn size (Y_vv -0.03..-0.09) with its candidate
  // withheld: no name can explain it. Without the term search the side-force residual is located
  // on v (the state test sees it through the excitation); with it, its form is found. (The false-
  // alarm rate of both: test_discrepancy_nulls.cc.)
  int located = 0, found = 0;
  const int seeds = 8;
  for (std::uint64_t s = 1; s <= static_cast<std::uint64_t>(seeds); ++s) {
    ident::test::HiddenEffects h;
    h.on = {"lateral_inflow"};
    h.scale = 3.0;
    ident::test::draw_magnitudes(h, s);
    ident::test::GeneratorOptions o;
    o.seed = s;
    const FlightData data = ident::test::generate_flight(ident::test::set1().model, ident::test::set1().vehicle, h, o);
    DiscrepancyOptions opt;
    opt.candidates = {"sensor_bias", "actuator_delay"};
    opt.term_search = false;
    const DiscrepancyResult closed =
        find_discrepancy(data, ident::test::set1().model, ident::test::set1().vehicle, opt);
    INFO("seed " << s << " Y_vv " << h.Y_vv << ", closed world: " << closed.summary);
    CHECK(closed.effects.empty());
    const bool side_force = std::any_of(closed.located.state.begin(), closed.located.state.end(),
                                        [](const StateFinding& f) { return f.output == "v_dot_star"; });
    located += closed.verdict == "unexplained" && side_force;
    opt.term_search = true;
    const DiscrepancyResult open = find_discrepancy(data, ident::test::set1().model, ident::test::set1().vehicle, opt);
    INFO("open world: " << open.summary);
    for (const auto& e : open.effects) CHECK(e.name == "term");  // never a library name
    const auto term = std::find_if(open.effects.begin(), open.effects.end(), [](const NamedEffect& e) {
      return e.name == "term" && e.equation == "Y" && e.expression == "v*abs(v)";
    });
    if (term != open.effects.end()) {
      // The coefficient is the side force's Y_vv [N s^2/m^2], within the closed loop's bias.
      CHECK(term->coefficient < 0.0);
      CHECK(std::fabs(term->coefficient - h.Y_vv) < 0.35 * std::fabs(h.Y_vv));
      CHECK(term->interval[0] < term->coefficient);
      CHECK(term->coefficient < term->interval[1]);
      ++found;
    }
  }
  std::printf(
      "discrepancy locator: lateral inflow (3x) with its candidate withheld located in %d of %d records, its "
      "form v*abs(v) in Y found in %d\n",
      located, seeds, found);
  CHECK(located >= seeds - 1);
  CHECK(found >= seeds - 1);
}

TEST_CASE("discrepancy: two candidates that explain the same thing give ambiguous, naming both",
          "[discrepancy][heavy]") {
  // The dihedral acts (thesis Table B.2 derivatives); the record's yaw rate follows the dihedral,
  // so yaw_coupling explains the same residual as dihedral_coupling.
  for (std::uint64_t s = 1; s <= 2; ++s) {
    const DiscrepancyResult r = run({"dihedral_coupling", "yaw_alias"}, s);
    INFO("seed " << s << ": " << r.summary);
    CHECK(r.verdict == "ambiguous");
    REQUIRE(r.ambiguous.size() == 1);
    std::vector<std::string> pair = r.ambiguous.front();
    std::sort(pair.begin(), pair.end());
    CHECK(pair == std::vector<std::string>{"dihedral_coupling", "yaw_coupling"});
  }
  // Without the alias it is named.
  const DiscrepancyResult r = run({"dihedral_coupling"}, 1);
  INFO(r.summary);
  CHECK(r.verdict == "effects");
  CHECK(names(r) == std::vector<std::string>{"dihedral_coupling"});
}

TEST_CASE("discrepancy: two hidden effects at once are both named", "[discrepancy][records]") {
  // Kinematic coupling (large) with forward-speed coupling of a drawn size: the first is named
  // every time; both in 7 of 8; never anything else.
  int both = 0;
  for (std::uint64_t s = 1; s <= 8; ++s) {
    const DiscrepancyResult r = run({"kinematic_coupling", "forward_speed_coupling"}, s);
    INFO("seed " << s << ": " << r.summary);
    CHECK(named(r, "kinematic_coupling"));
    for (const auto& n : names(r)) CHECK((n == "kinematic_coupling" || n == "forward_speed_coupling"));
    both += named(r, "forward_speed_coupling");
  }
  std::printf("discrepancy two hidden effects: both named in %d of 8 records\n", both);
  CHECK(both >= 7);
}

TEST_CASE("discrepancy: an effect too small to matter (2 % of its physical range) is not named",
          "[discrepancy][heavy]") {
  for (std::uint64_t s = 1; s <= 3; ++s) {
    const DiscrepancyResult r = run({"forward_speed_coupling"}, s, 0.02);
    INFO("seed " << s << ": " << r.summary);
    CHECK(r.effects.empty());
    CHECK((r.verdict == "none" || r.verdict == "unexplained"));
  }
}

TEST_CASE("discrepancy: every candidate is tried and reported, candidates the data cannot support are named as such",
          "[discrepancy]") {
  const DiscrepancyResult r = run({}, 5);
  for (const auto& spec : candidate_library()) {
    const auto it =
        std::find_if(r.candidates.begin(), r.candidates.end(), [&](const auto& t) { return t.name == spec.name; });
    REQUIRE(it != r.candidates.end());
    CHECK_FALSE(it->reason.empty());
  }
  const auto yaw =
      std::find_if(r.candidates.begin(), r.candidates.end(), [](const auto& t) { return t.name == "yaw_coupling"; });
  CHECK_FALSE(yaw->available);
  CHECK(yaw->reason == "the data has no r");
  // The library is the effect registry's definitions, in its order.
  REQUIRE(candidate_library().size() == nimble::effects::effect_registry().size());
  for (std::size_t i = 0; i < candidate_library().size(); ++i) {
    CHECK(candidate_library()[i].name == nimble::effects::effect_registry()[i].name());
  }
  DiscrepancyOptions bad;
  bad.candidates = {"lateral_inflow", "warp_drive"};
  CHECK_THROWS_WITH(
      find_discrepancy(ident::test::generate_flight(ident::test::set1().model, ident::test::set1().vehicle, {}, {}),
                       ident::test::set1().model, ident::test::set1().vehicle, bad),
      Catch::Contains("unknown candidate 'warp_drive'"));
}

TEST_CASE("discrepancy: the augmented model carries the named effect and reads back from its file", "[discrepancy]") {
  const DiscrepancyResult r = run({"kinematic_coupling"}, 2);
  REQUIRE(r.augmented_model.effects.count("kinematic_coupling") == 1);
  const std::string file = nimble::test::scratch_file("discrepancy", "augmented.yaml");
  write_model_yaml(r.augmented_model, file, {"test"});
  const DerivativeModel back = load_model(file);
  CHECK(back.effects.at("kinematic_coupling").at("Y_pw") ==
        Approx(r.augmented_model.effects.at("kinematic_coupling").at("Y_pw")).epsilon(1e-8));
  CHECK(back.at("Yp") == Approx(r.augmented.at("Yp").value).epsilon(1e-8));
  // An effect the registry does not know is read, and refused by the workflow, naming it.
  {
    std::ifstream in(file);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto at = text.find("effects:\n");
    REQUIRE(at != std::string::npos);
    text.insert(at + 9, "  warp_drive:\n    c: 1\n");
    std::ofstream(nimble::test::scratch_file("discrepancy", "bad.yaml")) << text;
  }
  const DerivativeModel bad = load_model(nimble::test::scratch_file("discrepancy", "bad.yaml"));
  CHECK_THROWS_WITH(find_discrepancy(ident::test::generate_flight(bad, ident::test::set1().vehicle, {}, {}), bad,
                                     ident::test::set1().vehicle, DiscrepancyOptions{}),
                    Catch::Contains("unknown effect 'warp_drive'"));
}

TEST_CASE(
    "instrumented_wald: a column that shares the equation's noise with the model's regressor is not taken for a "
    "term (least squares takes it), and a real one is found",
    "[discrepancy][instrumented]") {
  // The closed loop in miniature: the model's regressor x and a candidate w both carry the noise u
  // that drives the equation error (the states answer the process noise), and both move with an
  // exogenous excitation z. Least squares gives w a coefficient under the model; the test
  // instrumented by [1, z, z filtered] does not. 40 records of 4,000 samples each.
  using discrepancy_parts::instrumented_wald;
  using discrepancy_parts::Span;
  const Eigen::Index n = 4000;
  int iv_rejects_null = 0, iv_rejects_term = 0;
  double ls_mean = 0.0, iv_mean = 0.0;
  const int records = 40;
  for (int seed = 0; seed < records; ++seed) {
    std::mt19937_64 rng(9100 + seed);
    std::normal_distribution<double> n01(0.0, 1.0);
    Eigen::VectorXd z(n), z2(n), u(n), v(n);
    double a = 0.0, b = 0.0;
    for (Eigen::Index k = 0; k < n; ++k) {
      a = 0.98 * a + n01(rng);
      b = 0.9 * b + 0.1 * a;
      z[k] = a;
      z2[k] = b;
      u[k] = n01(rng);
      v[k] = 0.5 * n01(rng);
    }
    const Eigen::VectorXd x = z + 0.2 * u, w = z2 + u;
    Eigen::MatrixXd X(n, 2), Z(n, 3), C(n, 1);
    X << Eigen::VectorXd::Ones(n), x;
    Z << Eigen::VectorXd::Ones(n), z, z2;
    C.col(0) = w;
    const Span instruments(Z);
    const Eigen::VectorXd y0 = 1.5 * x + u + v, y1 = y0 + 0.3 * w;
    double c = 0.0, sigma = 0.0;
    if (instrumented_wald(X, y0, C, instruments, 20, &c, &sigma) <= 0.01) ++iv_rejects_null;
    iv_mean += c / records;
    if (instrumented_wald(X, y1, C, instruments, 20, nullptr, nullptr) <= 0.01) ++iv_rejects_term;
    Eigen::MatrixXd W(n, 3);
    W << X, w;
    ls_mean += W.colPivHouseholderQr().solve(y0)[2] / records;
  }
  INFO("least squares mean coefficient " << ls_mean << ", instrumented " << iv_mean
                                         << "; instrumented rejections at 1 %: " << iv_rejects_null << " of " << records
                                         << " under the model, " << iv_rejects_term << " with the term 0.3 w");
  CHECK(std::fabs(ls_mean) > 0.15);  // measured 0.23
  CHECK(std::fabs(iv_mean) < 0.05);
  CHECK(iv_rejects_null <= 3);  // binomial(40, 0.01): P(>= 4) < 1e-3
  CHECK(iv_rejects_term >= 36);
}
