// Output files whose every write is checked (core/output_file.h): the error names the file, the
// byte and the system's reason; a failed whole-file write leaves the old file; a failed log write
// cuts the file back to its last whole record. Writes fail here on /dev/full (ENOSPC) and past a
// file size limit (RLIMIT_FSIZE: EFBIG), set for this process only while a case runs.

#include <sys/resource.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>

#include <catch2/catch.hpp>

#include "core/output_file.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using nimble::OutputError;
using nimble::OutputFile;

namespace {

std::string scratch(const std::string& tag) { return nimble::test::scratch_dir("output_file_" + tag); }

std::string read_all(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A file size limit for this process while it lives (a write past it fails with EFBIG).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    std::signal(SIGXFSZ, SIG_IGN);
    ::getrlimit(RLIMIT_FSIZE, &old_);
    rlimit l = old_;
    l.rlim_cur = bytes;
    REQUIRE(::setrlimit(RLIMIT_FSIZE, &l) == 0);
  }
  ~FileSizeLimit() { ::setrlimit(RLIMIT_FSIZE, &old_); }

 private:
  rlimit old_{};
};

}  // namespace

TEST_CASE("write_file writes whole files and leaves no temporary file", "[output_file]") {
  const std::string d = scratch("whole");
  nimble::write_file(d + "/a.txt", "first\n");
  nimble::write_file(d + "/a.txt", "second\n");
  CHECK(read_all(d + "/a.txt") == "second\n");
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(d)) ++files;
  CHECK(files == 1);
  CHECK_THROWS_WITH(nimble::write_file(d + "/missing/b.txt", "x"), Contains(d + "/missing/b.txt"));
  fs::remove_all(d);
}

TEST_CASE("write_file past a file size limit names the file, the byte and EFBIG, and keeps the old file",
          "[output_file]") {
  const std::string d = scratch("efbig");
  const std::string f = d + "/model.yaml";
  nimble::write_file(f, "old content\n");
  const std::string big(10000, 'x');
  {
    FileSizeLimit limit(4096);
    try {
      nimble::write_file(f, big);
      FAIL("a write past the file size limit did not fail");
    } catch (const OutputError& e) {
      CHECK_THAT(e.what(), Contains(f) && Contains("at byte 4096 of 10000") && Contains("File too large"));
      CHECK(e.error_number() == EFBIG);
    }
  }
  CHECK(read_all(f) == "old content\n");
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(d)) ++files;
  CHECK(files == 1);  // no .partial left behind
  fs::remove_all(d);
}

TEST_CASE("write_file on a full device names ENOSPC", "[output_file]") {
  REQUIRE(fs::exists("/dev/full"));
  try {
    nimble::write_file("/dev/full", "a report\n");
    FAIL("a write to /dev/full did not fail");
  } catch (const OutputError& e) {
    CHECK_THAT(e.what(), Contains("/dev/full") && Contains("No space left on device"));
    CHECK(e.error_number() == ENOSPC);
  }
}

TEST_CASE("an OutputFile that cannot write ends on its last whole record", "[output_file]") {
  const std::string d = scratch("records");
  const std::string f = d + "/run.log";
  const std::string record(100, 'r');
  {
    FileSizeLimit limit(1050);  // ten whole records and half of the eleventh
    OutputFile out(f, 256);     // written in pieces that cut records
    int accepted = 0;
    try {
      for (int i = 0; i < 20; ++i) {
        out.append(record.data(), 40);
        out.append(record.data() + 40, 60);
        out.end_record();
        ++accepted;
      }
      out.close();
      FAIL("writing past the limit did not fail");
    } catch (const OutputError& e) {
      CHECK_THAT(e.what(), Contains(f) && Contains("File too large"));
      CHECK(e.offset() == 1050);
    }
    CHECK(out.failed());
    CHECK(out.kept_records() == 10);
    CHECK(out.kept_bytes() == 1000);
    CHECK(accepted >= 10);
    CHECK_THROWS_AS(out.append("x", 1), OutputError);  // takes nothing more
  }
  CHECK(fs::file_size(f) == 1000);
  fs::remove_all(d);
}

TEST_CASE("an OutputFile at its own size limit keeps its whole records before it", "[output_file]") {
  const std::string d = scratch("limit");
  const std::string f = d + "/run.log";
  OutputFile out(f, 64);
  out.set_max_bytes(250);
  const std::string record(30, 'a');
  int accepted = 0;
  try {
    for (int i = 0; i < 20; ++i) {
      out.append(record.data(), record.size());
      out.end_record();
      ++accepted;
    }
    FAIL("the limit was not kept");
  } catch (const OutputError& e) {
    CHECK_THAT(e.what(), Contains("limit of 250 bytes"));
  }
  CHECK(accepted == 8);
  CHECK(out.kept_records() == 8);
  CHECK(out.kept_bytes() == 240);
  CHECK(fs::file_size(f) == 240);
  fs::remove_all(d);
}

TEST_CASE("an OutputFile on a full device names ENOSPC and the file", "[output_file]") {
  OutputFile out("/dev/full", 16);
  try {
    for (int i = 0; i < 4; ++i) {
      out.append("0123456789", 10);
      out.end_record();
    }
    out.close();
    FAIL("writing to /dev/full did not fail");
  } catch (const OutputError& e) {
    CHECK_THAT(e.what(), Contains("/dev/full") && Contains("No space left on device"));
    CHECK(e.error_number() == ENOSPC);
  }
  CHECK(out.kept_records() == 0);
}

TEST_CASE("append_to_file adds lines and names a failure", "[output_file]") {
  const std::string d = scratch("append");
  nimble::append_to_file(d + "/jobs.txt", "1 a\n");
  nimble::append_to_file(d + "/jobs.txt", "2 b\n");
  CHECK(read_all(d + "/jobs.txt") == "1 a\n2 b\n");
  CHECK_THROWS_WITH(nimble::append_to_file("/dev/full", "x\n"), Contains("No space left on device"));
  fs::remove_all(d);
}

TEST_CASE("free_bytes_at looks at the nearest existing directory", "[output_file]") {
  CHECK(nimble::free_bytes_at(fs::temp_directory_path().string() + "/no/such/dir/x.lcmlog") > 0);
  CHECK(nimble::human_bytes(999) == "999 B");
  CHECK(nimble::human_bytes(298973) == "299.0 kB");
  CHECK(nimble::human_bytes(2100000) == "2.1 MB");
}
