// Unit tests of bad and short records (ident/data_check.h, whiteness on short data): a record
// that is not finite or not physical is refused by identify, validate and discrepancy (one
// flight or pooled), naming its first bad sample; a record too short for a diagnostic gets a
// note instead of an error.

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "ident/data_check.h"
#include "discrepancy/discrepancy.h"
#include "ident/identify.h"
#include "ident/synthetic.h"
#include "ident/validate.h"
#include "synthetic_flight.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

/// A 4 s synthetic set-1 flight (doublets from 0.3 s).
FlightData short_flight(double duration_s, std::uint64_t seed) {
  const SyntheticOptions o = ident::test::short_identification_flight(duration_s, seed);
  const DerivativeModel m = ident::test::set1_model();
  FlightData d = simulate_synthetic(m, load_vehicle(m.vehicle_file), o);
  d.source = "flight_" + std::to_string(seed) + ".csv";
  return d;
}

/// `d` with its states diverging from t = 1.5 s: p, v and phi grow as exp(6 (t - 1.5)), to
/// millions of rad/s by the end, as a simulation that went unstable.
FlightData diverged(FlightData d) {
  for (const char* s : {"p", "v", "phi"}) {
    Channel& c = d.channels.at(s);
    for (std::size_t k = 0; k < c.values.size(); ++k) {
      if (c.t_s[k] > 1.5) c.values[k] *= std::exp(6.0 * (c.t_s[k] - 1.5)) * 1e3;
    }
  }
  return d;
}

/// The first sample of `c` beyond `bound`, as the test sees it.
std::size_t first_beyond(const Channel& c, double bound) {
  for (std::size_t k = 0; k < c.values.size(); ++k) {
    if (!(std::fabs(c.values[k]) <= bound)) return k;
  }
  return c.values.size();
}

std::string time_text(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "at t = %.4f s", t);
  return buf;
}

template <typename F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const RefusedData& e) {
    return e.what();
  } catch (const std::exception& e) {
    FAIL("not a refusal: " << e.what());
  }
  FAIL("not refused");
  return "";
}

}  // namespace

TEST_CASE(
    "bad data: a diverged record is refused by identify, validate and discrepancy, alone or pooled, naming "
    "its first bad sample's time, channel and bound",
    "[data_check][bad_data]") {
  const DerivativeModel model = ident::test::set1_model();
  const Vehicle vehicle = load_vehicle(model.vehicle_file);
  REQUIRE(vehicle.data_bounds.rate_max_radps == 50.0);
  const FlightData good = short_flight(4.0, 3);
  const FlightData bad = diverged(good);
  // The first bad sample: p, which crosses 50 rad/s before v crosses 20 m/s and phi pi.
  const Channel& p = bad.at("p");
  const std::size_t k = first_beyond(p, 50.0);
  REQUIRE(k < p.values.size());
  CHECK(first_beyond(bad.at("v"), 20.0) >= k);
  CHECK(first_beyond(bad.at("phi"), M_PI) >= k);
  CHECK(std::fabs(p.values.back()) > 1e6);  // diverged to millions of rad/s

  const std::string expected_head = "refused: flight_3.csv: p = ";
  const std::string expected_where = time_text(p.t_s[k]) + " exceeds the physical bound 50 rad/s (vehicle file " +
                                     vehicle.file + ", bound data_bounds.rate_max_radps)";
  IdentOptions io;
  io.trim = model.trim;
  for (const std::string& message : {refusal([&] { identify(bad, vehicle, vehicle.file, io); }),
                                     refusal([&] { validate_open_loop(bad, model, vehicle, {}); }),
                                     refusal([&] { find_discrepancy(bad, model, vehicle, {}); }), refusal([&] {
                                       find_discrepancy(std::vector<FlightData>{good, bad}, model, vehicle, {});
                                     })}) {
    INFO(message);
    CHECK(message.rfind(expected_head, 0) == 0);
    CHECK(message.find(expected_where) != std::string::npos);
  }
  try {
    check_flight_data(bad, vehicle);
  } catch (const RefusedData& e) {
    CHECK(e.column() == "p");
    CHECK(e.row() == static_cast<int>(k + 1));
    CHECK(e.time_s() == p.t_s[k]);
  }
  CHECK_NOTHROW(check_flight_data(good, vehicle));
}

TEST_CASE("bad data: a NaN or infinite sample is refused wherever it is, naming its time and channel",
          "[data_check][bad_data]") {
  const DerivativeModel model = ident::test::set1_model();
  const Vehicle vehicle = load_vehicle(model.vehicle_file);
  const FlightData good = short_flight(4.0, 4);
  FlightData bad = good;
  Channel& v = bad.channels.at("v");
  const std::size_t k = 700;
  v.values[k] = std::numeric_limits<double>::quiet_NaN();
  bad.channels.at("delta_f").values[k + 10] = std::numeric_limits<double>::infinity();  // later: not named
  const std::string expected = "refused: flight_4.csv: v = nan " + time_text(v.t_s[k]) + " is not a finite number";
  IdentOptions io;
  io.trim = model.trim;
  for (const std::string& message : {refusal([&] { identify(bad, vehicle, vehicle.file, io); }),
                                     refusal([&] { validate_open_loop(bad, model, vehicle, {}); }), refusal([&] {
                                       find_discrepancy(std::vector<FlightData>{good, bad}, model, vehicle, {});
                                     })}) {
    // The first bad sample, then every bad sample counted by channel (BoundsTally::refusal()).
    CHECK(message.rfind(expected + "; 2 samples beyond the physical bounds of vehicle file " + vehicle.file +
                            ": v: 1 sample not finite (value or time), nan " + time_text(v.t_s[k]) +
                            "; delta_f: 1 sample",
                        0) == 0);
  }
  // An infinity is refused as well, even in a channel without a bound (psi), and even with every
  // bound switched off.
  FlightData inf = good;
  inf.channels["psi"] = Channel{inf.at("p").t_s, std::vector<double>(inf.at("p").t_s.size(), 0.0)};
  inf.channels.at("psi").values[k] = -std::numeric_limits<double>::infinity();
  Vehicle unbounded = vehicle;
  for (double* b : {&unbounded.data_bounds.rate_max_radps, &unbounded.data_bounds.speed_max_mps,
                    &unbounded.data_bounds.angle_max_rad}) {
    *b = DataBounds::kNone;
  }
  CHECK(
      refusal([&] {
        check_flight_data(inf, unbounded);
      }).rfind("refused: flight_4.csv: psi = -inf " + time_text(v.t_s[k]) + " is not a finite number; 1 sample ", 0) ==
      0);
  CHECK_NOTHROW(check_flight_data(diverged(good), unbounded));
}

TEST_CASE(
    "short record: identify, validate and discrepancy complete on 2.5 s, the whiteness test skipped with a "
    "note saying how long a record it needs",
    "[data_check][bad_data]") {
  const DerivativeModel model = ident::test::set1_model();
  const Vehicle vehicle = load_vehicle(model.vehicle_file);
  const FlightData d = short_flight(2.5, 5);
  // 50 lags of 28 samples (512 Hz, 9 Hz cut-off) need (50 + 1) 28 + 1 = 1429 samples, 2.79 s.
  CHECK(whiteness_min_samples(50, 28) == 1429);
  const std::string note =
      "whiteness skipped: needs at least 2.79 s of data at this decimation (50 lags of 28 samples, 1429 samples at "
      "512 Hz), the record has 2.50 s";
  IdentOptions io;
  io.trim = model.trim;
  const IdentResult r = identify(d, vehicle, vehicle.file, io);
  REQUIRE(r.fits.size() == 2);
  for (const auto& f : r.fits) {
    CHECK_FALSE(f.whiteness.tested);
    CHECK(f.whiteness.note == note);
  }
  CHECK(r.parameters.at("L_df").value == Approx(model.at("L_df")).epsilon(0.15));
  const ValidationResult v = validate_open_loop(d, model, vehicle, {});
  for (const auto& f : v.fits) CHECK(f.whiteness.note == note);
  DiscrepancyOptions dopt;
  dopt.candidates = {"sensor_bias"};
  const DiscrepancyResult dr = find_discrepancy(d, model, vehicle, dopt);
  REQUIRE(dr.notes.size() == 1);
  CHECK(dr.notes.front() == note);
  for (const auto& g : dr.gap) CHECK_FALSE(g.white_tested);
  // Long enough: tested, no note.
  const IdentResult longer = identify(short_flight(3.0, 5), vehicle, vehicle.file, io);
  for (const auto& f : longer.fits) CHECK(f.whiteness.tested);
}
