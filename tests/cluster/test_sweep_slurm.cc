// `rig sweep --backend slurm` on a real Slurm engine: each test case brings up a one-node cluster
// (munged, slurmctld, slurmd from Debian's packages, as root, in a temporary directory, on the
// loopback; tests/cluster/slurm_cluster.sh) and stops its daemons by PID at the end. Where the
// cluster cannot start the case fails with the daemons' own words: it never skips.
//
// The campaign: the identification train (3 s) on the models of sets 1 and 4, seeds 1-20: 40 runs.

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "../support/campaign_files.h"
#include "../support/rig_runs.h"

namespace fs = std::filesystem;
using nimble::test::csv_without_machine;
using nimble::test::json_without_machine;
using nimble::test::shell;
using nimble::test::slurp;

namespace {

const std::string kSource = std::string(RIG_SOURCE_DIR) + "/";
const std::string kClusterScript = kSource + "tests/cluster/slurm_cluster.sh";
const std::string kCampaign =
    kSource + "rig_configs/id_doublet_train_fast.yaml --seeds 1-20 --set duration_s=3 --vary model=" + kSource +
    "rig_configs/models/nimble_lateral_set1.yaml," + kSource +
    "rig_configs/models/nimble_lateral_set4.yaml --no-progress";

/// A one-node cluster for the life of the object; SLURM_CONF points the client commands at it.
class Cluster {
 public:
  explicit Cluster(const std::string& tag) : dir_(nimble::test::scratch_dir(tag) + "/cluster") {
    const std::string out = dir_ + ".start.txt";
    const int code = shell(kClusterScript + " start " + dir_ + " >" + out + " 2>&1");
    INFO(slurp(out));
    REQUIRE(code == 0);  // no Slurm, no test: fail loudly with the daemons' logs
    ::setenv("SLURM_CONF", (dir_ + "/slurm.conf").c_str(), 1);
  }
  ~Cluster() { shell(kClusterScript + " stop " + dir_ + " >/dev/null 2>&1"); }
  Cluster(const Cluster&) = delete;
  Cluster& operator=(const Cluster&) = delete;

 private:
  std::string dir_;
};

struct Outcome {
  int exit_code = -1;
  std::string output;
};

Outcome rig_sweep(const std::string& dir, const std::string& name, const std::string& args) {
  const std::string out = dir + "/" + name + ".txt";
  const int code = shell(std::string(RIG_BIN) + " sweep " + args + " >" + out + " 2>&1");
  return {code, slurp(out)};
}

/// The local reference: one job, campaign in DIR/local.
std::string local_reference(const std::string& d) {
  const Outcome local =
      rig_sweep(d, "local", kCampaign + " --jobs 1 --dir " + d + "/local --report " + d + "/local_report");
  INFO(local.output);
  REQUIRE(local.exit_code == 0);
  return d + "/local";
}

void require_same_result(const std::string& a, const std::string& b) {
  CHECK(json_without_machine(a + "/result.json") == json_without_machine(b + "/result.json"));
  CHECK(csv_without_machine(a + "/result.csv") == csv_without_machine(b + "/result.csv"));
}

struct FileStamp {
  ino_t inode = 0;
  long long mtime_ns = 0;
};

std::map<std::string, FileStamp> run_files(const std::string& campaign) {
  std::map<std::string, FileStamp> files;
  for (const auto& e : fs::directory_iterator(campaign + "/runs")) {
    struct stat st {};
    ::stat(e.path().c_str(), &st);
    files[e.path().filename().string()] = {st.st_ino, st.st_mtim.tv_sec * 1000000000LL + st.st_mtim.tv_nsec};
  }
  return files;
}

std::string job_of(const std::string& campaign, int line) {
  std::ifstream in(campaign + "/slurm/jobs.txt");
  std::string job, spec;
  for (int k = 0; k <= line; ++k) {
    if (!(in >> job >> spec)) return "";
  }
  return job;
}

std::string where_of(const std::string& campaign, std::size_t run) {
  char name[32];
  std::snprintf(name, sizeof name, "/runs/run-%06zu.json", run);
  std::ifstream in(campaign + name);
  std::string campaign_line, result;  // the first line names the campaign (campaign/result_files.h)
  std::getline(in, campaign_line);
  std::getline(in, result);
  return nlohmann::json::parse(result)["machine"]["where"].get<std::string>();
}

}  // namespace

TEST_CASE("slurm: a 40-run campaign gives the local backend's result, whatever the jobs and the chunks", "[cluster]") {
  Cluster cluster("slurm_same");
  const std::string d = nimble::test::scratch_path("slurm_same");
  const std::string local = local_reference(d);

  const Outcome two_jobs = rig_sweep(d, "local2", kCampaign + " --jobs 2 --dir " + d + "/local2");
  INFO(two_jobs.output);
  REQUIRE(two_jobs.exit_code == 0);
  require_same_result(local, d + "/local2");

  // Six array tasks of 7 runs (the last of 5), one run at a time each.
  const Outcome slurm7 = rig_sweep(
      d, "slurm7", kCampaign + " --backend slurm --chunk 7 --dir " + d + "/slurm7 --report " + d + "/slurm7_report");
  INFO(slurm7.output);
  REQUIRE(slurm7.exit_code == 0);
  CHECK(slurm7.output.find("array tasks 0-5 of 6, up to 7 runs each") != std::string::npos);
  CHECK(slurm7.output.find("40 runs: 2 parameter sets x 20 seeds (1-20)") != std::string::npos);
  require_same_result(local, d + "/slurm7");
  // The runs ran in Slurm's tasks: run 8 in task 1.
  CHECK(where_of(d + "/slurm7", 8) == "slurm job " + job_of(d + "/slurm7", 0) + " task 1");
  // The report is the same file for file, byte for byte.
  for (const char* file : {"envelopes.csv", "report.json", "set-1.svg", "set-2.svg", "index.html"}) {
    INFO(file);
    CHECK(slurp(d + "/slurm7_report/" + file) == slurp(d + "/local_report/" + file));
  }

  // One task of all 40 runs, two at a time on its two CPUs.
  const Outcome slurm40 =
      rig_sweep(d, "slurm40", kCampaign + " --backend slurm --chunk 40 --cpus-per-task 2 --dir " + d + "/slurm40");
  INFO(slurm40.output);
  REQUIRE(slurm40.exit_code == 0);
  require_same_result(local, d + "/slurm40");
  const std::string script = slurp(d + "/slurm40/slurm/sweep.sbatch");
  CHECK(script.find("#SBATCH --cpus-per-task=2") != std::string::npos);
  CHECK(script.find("sweep task '" + d + "/slurm40' --task \"$SLURM_ARRAY_TASK_ID\"") != std::string::npos);
}

TEST_CASE("slurm: a cancelled array task is named with its runs, and --resume finishes the campaign", "[cluster]") {
  Cluster cluster("slurm_cancel");
  const std::string d = nimble::test::scratch_path("slurm_cancel");
  const std::string local = local_reference(d);
  const std::string c = d + "/slurm";

  // Four tasks of 10 runs; two CPUs run two at a time, so task 3 is still pending when it is cancelled.
  const std::string cmd = std::string(RIG_BIN) + " sweep " + kCampaign + " --backend slurm --chunk 10 --dir " + c +
                          " >" + d + "/waiting.txt 2>&1; echo $? >" + d + "/waiting.exit";
  std::thread waiting([cmd] { shell(cmd); });
  std::string job;
  for (int k = 0; k < 300 && job.empty(); ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    job = job_of(c, 0);
  }
  REQUIRE(!job.empty());
  CHECK(shell("scancel " + job + "_3") == 0);
  // While it waits for its tasks, the submitting rig sweep holds the directory (the tasks write their
  // runs beside it): a second sweep on it is refused at once, naming the holder.
  const Outcome second = rig_sweep(d, "second", "--resume " + c);
  CHECK(second.exit_code == 2);
  CHECK(second.output.find("the campaign directory " + c + " is being written by another process (pid ") !=
        std::string::npos);
  waiting.join();
  const std::string said = slurp(d + "/waiting.txt");
  INFO(said);
  CHECK(std::stoi(slurp(d + "/waiting.exit")) == 3);
  CHECK(said.find("job " + job +
                  " task 3 (runs 30-39 (set 2 seed 11 to set 2 seed 20)) never started (CANCELLED while pending") !=
        std::string::npos);
  CHECK(said.find("10 of 10 runs without a result (set 2 seed 11, set 2 seed 12, set 2 seed 13, set 2 seed 14, ...)") !=
        std::string::npos);
  CHECK(said.find("rig sweep --resume " + c) != std::string::npos);
  const auto before = run_files(c);
  CHECK(before.size() == 30);

  // collect names what is missing and merges nothing.
  const Outcome collect = rig_sweep(d, "collect", "collect " + c);
  INFO(collect.output);
  CHECK(collect.exit_code == 3);
  CHECK(collect.output.find("10 of 40 runs have no result (set 2 seed 11, ") != std::string::npos);
  CHECK(!fs::exists(c + "/result.json"));

  const Outcome resumed = rig_sweep(d, "resume", "--resume " + c + " --no-progress");
  INFO(resumed.output);
  REQUIRE(resumed.exit_code == 0);
  CHECK(resumed.output.find("10 of 40 runs without a result") != std::string::npos);
  CHECK(resumed.output.find("(array tasks 3 of 4,") != std::string::npos);
  require_same_result(local, c);
  // Nothing finished was flown again: the 30 files are the same files, untouched.
  const auto after = run_files(c);
  CHECK(after.size() == 40);
  for (const auto& [name, stamp] : before) {
    INFO(name);
    REQUIRE(after.count(name) == 1);
    CHECK(after.at(name).inode == stamp.inode);
    CHECK(after.at(name).mtime_ns == stamp.mtime_ns);
  }
  CHECK(where_of(c, 35) == "slurm job " + job_of(c, 1) + " task 3");
  CHECK(where_of(c, 5) == "slurm job " + job + " task 0");
}

TEST_CASE("slurm: a task that exits non-zero is named, and --retries resubmits only its runs", "[cluster]") {
  Cluster cluster("slurm_retry");
  const std::string d = nimble::test::scratch_path("slurm_retry");
  const std::string local = local_reference(d);
  const std::string c = d + "/slurm";
  // The rig as the nodes see it: a wrapper whose task 1 fails once (a node that lost its disk, say).
  const std::string wrapper = d + "/flaky-rig";
  {
    std::ofstream w(wrapper);
    w << "#!/bin/sh\n"
      << "if [ \"$SLURM_ARRAY_TASK_ID\" = 1 ] && [ ! -e " << d << "/failed-once ]; then\n"
      << "  touch " << d << "/failed-once; echo 'flaky-rig: task 1 fails this once' >&2; exit 7\n"
      << "fi\n"
      << "exec " << RIG_BIN << " \"$@\"\n";
  }
  fs::permissions(wrapper, fs::perms::owner_all);
  const Outcome r =
      rig_sweep(d, "retry", kCampaign + " --backend slurm --chunk 10 --retries 1 --rig " + wrapper + " --dir " + c);
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const std::string job = job_of(c, 0);
  CHECK(r.output.find("job " + job + " task 1 (runs 10-19 (set 1 seed 11 to set 1 seed 20)) FAILED exit 7:0") !=
        std::string::npos);
  CHECK(r.output.find("retry 1 of 1") != std::string::npos);
  // The retry is task 1 alone.
  CHECK(slurp(c + "/slurm/jobs.txt") == job + " 0-3\n" + job_of(c, 1) + " 1\n");
  require_same_result(local, c);
  CHECK(where_of(c, 12) == "slurm job " + job_of(c, 1) + " task 1");
}
