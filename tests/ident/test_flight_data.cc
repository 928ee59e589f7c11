// Unit tests of the flight-data CSV reader and writer: every bad-data case
// names its row, file line and column.

#include <unistd.h>

#include <filesystem>
#include <cmath>
#include <fstream>
#include <map>
#include <string>

#include <catch2/catch.hpp>

#include "ident/flight_data.h"
#include "tests/support/scratch.h"

using namespace nimble::ident;

namespace {

const std::string kHeader = "t,p,v,phi,delta_f,delta_t\n";

/// Three comment lines, the header (line 4) and `rows` (lines 5...).
std::string csv_with(const std::string& rows, const std::string& header = kHeader) {
  return "# flight 12\n# units: SI, delta_t in %\n#\n" + header + rows;
}

const std::string kGoodRows =
    "0.000,0.1,0.01,0.001,1.0,0.0\n"
    "0.002,0.2,0.02,0.002,2.0,0.5\n"
    "0.004,0.3,0.03,0.003,3.0,1.0\n";

/// Parses `text` and returns the DataError it must throw.
DataError error_of(const std::string& text) {
  try {
    parse_flight_csv(text, "flight.csv");
  } catch (const DataError& e) {
    return e;
  }
  FAIL("no DataError thrown");
  return DataError("", -1, -1, "", "");
}

}  // namespace

TEST_CASE("a CSV with comments, optional columns in any order and blank lines is read", "[flight_data]") {
  const std::string text = csv_with("0,0.1,0.01,0.001,1,0,0.2,0.05\n\n0.5,0.2,0.02,0.002,2,0.5,0.3,0.06\r\n",
                                    "t, p ,v,phi,delta_f,delta_t,r,phi_sp\n");
  const FlightData d = parse_flight_csv(text, "flight.csv");
  CHECK(d.source == "flight.csv");
  CHECK(d.channels.size() == 7);
  REQUIRE(d.has("p"));
  REQUIRE(d.has("r"));
  REQUIRE(d.has("phi_sp"));
  CHECK_FALSE(d.has("t"));
  CHECK(d.at("p").values == std::vector<double>{0.1, 0.2});
  CHECK(d.at("phi_sp").values == std::vector<double>{0.05, 0.06});
  CHECK(d.at("r").t_s == std::vector<double>{0.0, 0.5});
  CHECK(d.min_samples() == 2);
}

TEST_CASE("a CSV from a spreadsheet program: byte order mark and quoted header names", "[flight_data]") {
  const std::string body = "0,0.1,0.01,0.001,1,0\n0.5,0.2,0.02,0.002,2,0.5\n";
  const FlightData plain = parse_flight_csv("t,p,v,phi,delta_f,delta_t\n" + body, "plain.csv");
  const FlightData bom = parse_flight_csv("\xEF\xBB\xBFt,p,v,phi,delta_f,delta_t\n" + body, "bom.csv");
  const FlightData quoted =
      parse_flight_csv("\xEF\xBB\xBF\"t\",\"p\",\"v\",\"phi\",\"delta_f\",\"delta_t\"\n" + body, "quoted.csv");
  for (const FlightData* d : {&bom, &quoted}) {
    REQUIRE(d->has("p"));
    CHECK(d->at("p").values == plain.at("p").values);
    CHECK(d->at("delta_t").t_s == plain.at("delta_t").t_s);
  }
}

TEST_CASE("CSV written by format_flight_csv reads back bit for bit", "[flight_data]") {
  FlightData d;
  d.source = "memory";
  const std::vector<double> t{0.0, 1.0 / 3.0, 2.0 / 3.0};
  for (const char* name : {"p", "v", "phi", "delta_f", "delta_t", "delta_d", "phi_sp"}) {
    d.channels[name] = Channel{t, {std::sqrt(2.0), -1e-300, 123456789.123456789}};
  }
  const std::string text = format_flight_csv(d);
  CHECK(text.rfind("# units: t [s], p [rad/s]", 0) == 0);
  const FlightData back = parse_flight_csv(text, "back.csv");
  REQUIRE(back.channels.size() == d.channels.size());
  for (const auto& [name, c] : d.channels) {
    INFO(name);
    CHECK(back.at(name).t_s == c.t_s);
    CHECK(back.at(name).values == c.values);
  }
  // through a file as well
  const std::filesystem::path path = nimble::test::scratch_file("flight", "flight.csv");
  write_flight_csv(d, path.string());
  CHECK(read_flight_csv(path.string()).at("delta_d").values == d.at("delta_d").values);
  std::filesystem::remove(path);
}

TEST_CASE("the CSV writer refuses data it cannot represent", "[flight_data]") {
  FlightData d;
  d.source = "memory";
  for (const char* name : {"p", "v", "phi", "delta_f", "delta_t"}) d.channels[name] = Channel{{0.0, 1.0}, {0.0, 0.0}};
  d.channels["v"].t_s = {0.0, 2.0};
  CHECK_THROWS_WITH(format_flight_csv(d), Catch::Contains("'v'") && Catch::Contains("resample"));
  d.channels["v"].t_s = {0.0, 1.0};
  d.channels.erase("delta_t");
  CHECK_THROWS_WITH(format_flight_csv(d), Catch::Contains("delta_t"));
}

TEST_CASE("every bad-data case names the row, the file line and the column", "[flight_data]") {
  SECTION("missing required column") {
    const DataError e = error_of(csv_with("0,0.1,0.01,0.001,1\n", "t,p,v,phi,delta_f\n"));
    CHECK(e.column() == "delta_t");
    CHECK(e.line() == 4);
    CHECK(std::string(e.what()).find("missing required column delta_t") != std::string::npos);
  }
  SECTION("several missing columns are all named") {
    const DataError e = error_of(csv_with("0,0.1,1\n", "t,p,delta_f\n"));
    CHECK(std::string(e.what()).find("v, phi, delta_t") != std::string::npos);
  }
  SECTION("unknown column") {
    const DataError e = error_of(csv_with("0,0.1,0.01,0.001,1,0,5\n", "t,p,v,phi,delta_f,delta_t,roll_rate\n"));
    CHECK(e.column() == "roll_rate");
    CHECK(e.line() == 4);
    CHECK(std::string(e.what()).find("unknown column roll_rate") != std::string::npos);
  }
  SECTION("duplicate column") {
    const DataError e = error_of(csv_with("0,0.1,0.01,0.001,1,0,5\n", "t,p,v,phi,delta_f,delta_t,p\n"));
    CHECK(e.column() == "p");
    CHECK(std::string(e.what()).find("twice") != std::string::npos);
  }
  SECTION("non-numeric cell") {
    const DataError e = error_of(csv_with(kGoodRows + "0.006,0.4,abc,0.004,4.0,1.5\n"));
    CHECK(e.row() == 4);
    CHECK(e.line() == 8);
    CHECK(e.column() == "v");
    CHECK(std::string(e.what()) == "flight.csv:8: row 4, column 'v': value 'abc' is not a number");
  }
  SECTION("a number followed by a unit") {
    const DataError e = error_of(csv_with("0,0.1 rad/s,0.01,0.001,1,0\n"));
    CHECK(e.row() == 1);
    CHECK(e.column() == "p");
  }
  SECTION("NaN") {
    const DataError e = error_of(csv_with(kGoodRows + "0.006,0.4,0.04,nan,4.0,1.5\n"));
    CHECK(e.row() == 4);
    CHECK(e.column() == "phi");
    CHECK(std::string(e.what()).find("not a finite number") != std::string::npos);
  }
  SECTION("infinity") {
    const DataError e = error_of(csv_with("0,0.1,0.01,0.001,-inf,0\n0.1,0.1,0.01,0.001,1,0\n"));
    CHECK(e.row() == 1);
    CHECK(e.line() == 5);
    CHECK(e.column() == "delta_f");
  }
  SECTION("overflow") {
    const DataError e = error_of(csv_with("0,0.1,0.01,0.001,1e999,0\n0.1,0.1,0.01,0.001,1,0\n"));
    CHECK(e.column() == "delta_f");
  }
  SECTION("empty cell") {
    const DataError e = error_of(csv_with(kGoodRows + "0.006,0.4,0.04,0.004,,1.5\n"));
    CHECK(e.row() == 4);
    CHECK(e.column() == "delta_f");
    CHECK(std::string(e.what()).find("empty cell") != std::string::npos);
  }
  SECTION("wrong number of cells") {
    const DataError e = error_of(csv_with(kGoodRows + "0.006,0.4,0.04\n"));
    CHECK(e.row() == 4);
    CHECK(e.line() == 8);
    CHECK(std::string(e.what()).find("has 3 cells, the header has 6") != std::string::npos);
  }
  SECTION("time not increasing") {
    const DataError e = error_of(csv_with(kGoodRows + "0.004,0.4,0.04,0.004,4.0,1.5\n"));
    CHECK(e.row() == 4);
    CHECK(e.line() == 8);
    CHECK(e.column() == "t");
    CHECK(std::string(e.what()).find("does not increase") != std::string::npos);
  }
  SECTION("time going back") {
    const DataError e = error_of(csv_with("1,0,0,0,0,0\n0.5,0,0,0,0,0\n"));
    CHECK(e.row() == 2);
    CHECK(e.column() == "t");
  }
  SECTION("a comment after the header is not a number") {
    const DataError e = error_of(csv_with(kGoodRows + "# late comment\n"));
    CHECK(e.row() == 4);
  }
  SECTION("too few rows") {
    const DataError e = error_of(csv_with("0,0.1,0.01,0.001,1,0\n"));
    CHECK(std::string(e.what()).find("1 data rows, needs at least 2") != std::string::npos);
  }
  SECTION("no header") {
    const DataError e = error_of("# only a comment\n");
    CHECK(std::string(e.what()).find("no header") != std::string::npos);
  }
}

TEST_CASE("a missing file is named", "[flight_data]") {
  CHECK_THROWS_WITH(read_flight_csv("/nonexistent/flight.csv"), Catch::Contains("/nonexistent/flight.csv"));
}

TEST_CASE("validate_flight_data names channel and sample of a log-reader record", "[flight_data]") {
  FlightData d;
  d.source = "log.lcm";
  d.channels["p"] = Channel{{0.0, 0.002, 0.002}, {0.0, 0.1, 0.2}};
  try {
    validate_flight_data(d);
    FAIL("no error");
  } catch (const DataError& e) {
    CHECK(e.column() == "p");
    CHECK(e.row() == 3);
  }
  d.channels["p"] = Channel{{0.0, 0.002}, {0.0}};
  CHECK_THROWS_AS(validate_flight_data(d), DataError);
}

TEST_CASE("flight_data_from_columns checks a user's columns on one time base and names what is wrong",
          "[flight_data]") {
  const std::vector<double> t{0.0, 0.01, 0.02};
  const std::vector<double> x{0.1, 0.2, 0.3};
  std::map<std::string, std::vector<double>> columns{{"p", x}, {"v", x}, {"phi", x}, {"delta_f", x}, {"delta_t", x}};
  const FlightData d = flight_data_from_columns("arrays", t, columns);
  CHECK(d.source == "arrays");
  CHECK(d.channels.size() == 5);
  CHECK(d.at("phi").t_s == t);
  CHECK(d.at("phi").values == x);
  // The time base is checked first and named "t", with the sample.
  try {
    flight_data_from_columns("arrays", {0.0, 0.01, 0.01}, columns);
    FAIL("no error");
  } catch (const DataError& e) {
    CHECK(e.column() == "t");
    CHECK(e.row() == 3);
    CHECK(e.problem().find("does not increase") != std::string::npos);
  }
  auto bad = columns;
  bad["phi"][1] = std::nan("");
  try {
    flight_data_from_columns("arrays", t, bad);
    FAIL("no error");
  } catch (const DataError& e) {
    CHECK(e.column() == "phi");
    CHECK(e.row() == 2);
  }
  bad = columns;
  bad.erase("delta_t");
  CHECK_THROWS_WITH(flight_data_from_columns("arrays", t, bad), Catch::Contains("missing required channel 'delta_t'"));
  bad = columns;
  bad["roll"] = x;
  CHECK_THROWS_WITH(flight_data_from_columns("arrays", t, bad),
                    Catch::Contains("unknown channel 'roll'") && !Catch::Contains("known: t,"));
  bad = columns;
  bad["v"].pop_back();
  CHECK_THROWS_WITH(flight_data_from_columns("arrays", t, bad), Catch::Contains("'v' has 2 samples, 't' has 3"));
}
