// A campaign's parts as units: which run flies which set and seed, the array tasks' chunks and
// sbatch's --array list, the manifest written and read back, a damaged manifest, the scenario's
// cluster section checked, and atomic result files.

#include <unistd.h>

#include <cstdlib>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "core/output_file.h"
#include "campaign/campaign.h"
#include "campaign/slurm.h"
#include "campaign/worker_pool.h"
#include "scenario/scenario.h"
#include "tests/support/scratch.h"

using namespace nimble::launcher;
using namespace nimble::campaign;
namespace fs = std::filesystem;

namespace {

const std::string kSource = std::string(RIG_SOURCE_DIR) + "/";

std::string scratch(const std::string& tag) { return nimble::test::scratch_dir("campaign_" + tag); }

std::string slurp(const std::string& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

TEST_CASE("campaign: run i flies set i / S with seed A + i % S, and chunks cover every run once",
          "[launcher][campaign]") {
  Campaign c;
  c.sets = parameter_sets({parse_vary("model=a,b,c")});
  c.first_seed = 11;
  c.last_seed = 17;  // S = 7
  c.cluster.chunk_size = 5;
  REQUIRE(c.run_count() == 21);
  CHECK(c.set_of(0) == 0);
  CHECK(c.seed_of(0) == 11);
  CHECK(c.set_of(6) == 0);
  CHECK(c.seed_of(6) == 17);
  CHECK(c.set_of(7) == 1);
  CHECK(c.seed_of(7) == 11);
  CHECK(c.set_of(20) == 2);
  CHECK(c.seed_of(20) == 17);
  CHECK(c.run_name(9) == "set 2 seed 13");
  REQUIRE(c.chunk_count() == 5);
  std::vector<int> seen(c.run_count(), 0);
  for (std::size_t t = 0; t < c.chunk_count(); ++t) {
    for (const std::size_t i : c.chunk(t)) {
      ++seen[i];
      CHECK(c.task_of(i) == t);
    }
  }
  CHECK(std::count(seen.begin(), seen.end(), 1) == 21);
  CHECK(c.chunk(4) == std::vector<std::size_t>{20});
  CHECK(c.chunk(5).empty());
}

TEST_CASE("campaign: sbatch's --array list of the tasks", "[launcher][campaign]") {
  CHECK(array_spec({0, 1, 2, 3}) == "0-3");
  CHECK(array_spec({7}) == "7");
  CHECK(array_spec({9, 3, 4, 7, 8, 3}) == "3-4,7-9");
  CHECK(array_spec({0, 2, 4}) == "0,2,4");
  CHECK(array_spec({}).empty());
}

TEST_CASE("campaign: the manifest is written once and read back as it was made", "[launcher][campaign]") {
  const std::string d = scratch("manifest");
  CampaignRequest req;
  req.sweep.base.scenario_file = kSource + "rig_configs/id_doublet_train_fast.yaml";
  req.sweep.base.overrides = {{"duration_s", "2"}};
  req.sweep.vary = {parse_vary("summary.hover_phi_deg=4,6")};
  req.sweep.first_seed = 3;
  req.sweep.last_seed = 5;
  req.dir = d + "/c";
  req.backend = kBackendSlurm;
  req.cluster.partition = "short";
  req.cluster.time_limit = "0-00:10:00";
  req.cluster.cpus_per_task = 2;
  req.report = true;
  Campaign made = create_campaign(req);
  CHECK(made.files().made());
  CHECK(made.files().held());
  CHECK(made.cluster.chunk_size == 100);  // in process: the default
  CHECK(made.trace_hz == 50.0);
  const Campaign c = load_campaign(d + "/c");
  CHECK(c.dir == made.dir);
  CHECK(c.scenario == "id_doublet_train_fast");
  CHECK(c.run_count() == 6);
  CHECK(c.sets.size() == 2);
  CHECK(c.sets[1].label == "summary.hover_phi_deg=6");
  CHECK(c.set_digests == made.set_digests);
  CHECK(c.set_digests[0] != c.set_digests[1]);
  REQUIRE(c.overrides.size() == 1);
  CHECK(c.overrides[0].key_path == "duration_s");
  CHECK(c.overrides[0].value == "2");
  CHECK(c.cluster.partition == "short");
  CHECK(c.cluster.time_limit == "0-00:10:00");
  CHECK(c.cluster.cpus_per_task == 2);
  CHECK(c.backend == kBackendSlurm);
  CHECK(c.working_dir == fs::current_path().string());
  CHECK_NOTHROW(check_campaign_inputs(c));
  CHECK(missing_runs(c).size() == 6);
  // One writer: the directory is held while the campaign that took it lives, even by this process.
  CHECK_THROWS_WITH(create_campaign(req), Catch::Contains("the campaign directory " + d + "/c is being written by") &&
                                              Catch::Contains("pid " + std::to_string(::getpid())));
  CHECK(!c.files().held());  // load_campaign takes nothing (an array task beside the holder)
  made = Campaign{};         // released
  {
    const Campaign again = create_campaign(req);  // the same campaign: taken to be finished
    CHECK(!again.files().made());
    CHECK(again.created_unix_s == c.created_unix_s);
    CHECK(again.files().identity() == c.files().identity());
    req.sweep.last_seed = 6;
    CHECK_THROWS_WITH(create_campaign(req), Catch::Contains("is being written by"));
  }
  CHECK_THROWS_WITH(create_campaign(req),
                    Catch::Contains(d + "/c holds another campaign: its last_seed is 5, this one's 6"));

  const std::string script = slurp(write_batch_script(c));
  CHECK(script.find("#SBATCH --partition=short\n") != std::string::npos);
  CHECK(script.find("#SBATCH --time=0-00:10:00\n") != std::string::npos);
  CHECK(script.find("#SBATCH --cpus-per-task=2\n") != std::string::npos);
  CHECK(script.find("#SBATCH --account") == std::string::npos);  // none given: the user's default

  // A damaged manifest is named with what is wrong.
  std::string text = slurp(d + "/c/campaign.json");
  text.replace(text.find("\"first_seed\""), 12, "\"first_seex\"");
  std::ofstream(d + "/c/campaign.json") << text;
  CHECK_THROWS_WITH(load_campaign(d + "/c"), Catch::Contains("damaged campaign manifest " + d + "/c/campaign.json") &&
                                                 Catch::Contains("first_seed"));
  CHECK_THROWS_WITH(load_campaign(d), Catch::Contains("no campaign in " + d));
}

TEST_CASE("campaign: result files are written whole or not at all", "[launcher][campaign]") {
  const std::string d = scratch("atomic");
  nimble::write_file(d + "/a.json", "{\"x\": 1}\n");
  CHECK(slurp(d + "/a.json") == "{\"x\": 1}\n");
  nimble::write_file(d + "/a.json", "{\"x\": 2}\n");
  CHECK(slurp(d + "/a.json") == "{\"x\": 2}\n");
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(d)) files += e.is_regular_file();
  CHECK(files == 1);  // no temporary left behind
  CHECK_THROWS_WITH(nimble::write_file(d + "/missing/b.json", "x"), Catch::Contains(d + "/missing/b.json"));
}

TEST_CASE("campaign: the scenario's cluster section is checked like any other", "[launcher][campaign]") {
  const std::string base = kSource + "rig_configs/hover.yaml";
  const auto cluster = [&](const std::vector<nimble::Override>& ov) {
    return cluster_settings_from(nimble::load_scenario(base, ov));
  };
  CHECK(cluster({}).time_limit == "01:00:00");
  const ClusterSettings c =
      cluster({{"cluster", "{partition: gpu, time_limit: \"2-00:00:00\", cpus_per_task: 4, chunk_size: 10}"}});
  CHECK(c.partition == "gpu");
  CHECK(c.time_limit == "2-00:00:00");
  CHECK(c.cpus_per_task == 4);
  CHECK(c.chunk_size == 10);
  CHECK_THROWS_WITH(cluster({{"cluster.time_limit", "an hour"}}),
                    Catch::Contains("time_limit") && Catch::Contains("MM:SS"));
  CHECK_THROWS_WITH(cluster({{"cluster.cpus_per_task", "0"}}), Catch::Contains("cpus_per_task"));
  CHECK_THROWS_WITH(cluster({{"cluster.partion", "short"}}), Catch::Contains("unknown key"));
}

// ---------------------------------------------------------------------------------------------
// The one worker pool every campaign flies its runs in.

TEST_CASE("worker pool: every item once, results by index, each reported as it finishes, a crash costs one item",
          "[campaign][worker_pool]") {
  const std::size_t n = 23;
  std::vector<int> started(n, 0), finished(n, 0);
  std::vector<std::size_t> done_seen;
  PoolWork pool;
  pool.work = [](std::size_t i) -> std::string {
    if (i == 7) ::abort();                               // the worker dies on item 7
    if (i == 11) throw std::runtime_error("bad\nitem");  // an item that fails, in words
    return "item " + std::to_string(i) + " in " + std::to_string(::getpid());
  };
  pool.died = [](std::size_t i, const std::string& how) { return "died on " + std::to_string(i) + ": " + how; };
  pool.started = [&](std::size_t i) { ++started.at(i); };
  pool.finished = [&](std::size_t i, const std::string& line, std::size_t done) {
    ++finished.at(i);
    done_seen.push_back(done);
    CHECK(!line.empty());
  };
  const std::vector<std::string> results = run_in_workers(n, 3, pool);
  REQUIRE(results.size() == n);
  std::set<std::string> pids;
  for (std::size_t i = 0; i < n; ++i) {
    INFO("item " << i);
    CHECK(started[i] == 1);
    CHECK(finished[i] == 1);
    if (i == 7) {
      CHECK(results[i] == "died on 7: killed by signal 6");
    } else if (i == 11) {
      CHECK(results[i] == "error bad item");
    } else {
      REQUIRE(results[i].rfind("item " + std::to_string(i) + " in ", 0) == 0);
      pids.insert(results[i].substr(results[i].rfind(' ') + 1));
    }
  }
  // Forked once each, not per item: three workers and the one that replaced the dead one.
  CHECK(pids.size() <= 4);
  CHECK(pids.count(std::to_string(::getpid())) == 0);
  for (std::size_t k = 0; k < done_seen.size(); ++k) CHECK(done_seen[k] == k + 1);
}

// The one result model of a campaign directory (result_files.h).

TEST_CASE("result files: a campaign directory takes its own manifest again and refuses another, naming the key",
          "[campaign][result_files]") {
  const std::string base = scratch("results");
  const std::string dir = base + "/c";
  const Manifest manifest{"test", {{"scenario_digest", "00aa"}, {"clock", "inprocess"}}, {}};
  std::string identity;
  {
    const ResultFiles files = open_result_dir(dir, manifest);
    CHECK(files.made());
    CHECK(fs::is_directory(files.runs_dir()));
    CHECK(fs::exists(files.manifest_file()));
    files.write("seed-3", "three");
    CHECK(files.has("seed-3"));
    CHECK(files.read("seed-3") == std::optional<std::string>("three"));
    CHECK(!files.read("seed-4"));
    std::ofstream(files.runs_dir() + "/seed-4.json.host.1.partial") << "half";
    // One writer: held while it lives (this process's second open is refused like any other's).
    CHECK_THROWS_WITH(open_result_dir(dir, manifest),
                      Catch::Contains("the campaign directory " + dir + " is being written by") &&
                          Catch::Contains("pid " + std::to_string(::getpid())));
    identity = files.identity();
    // A writer beside the holder (an array task) takes nothing and writes this campaign's results.
    const ResultFiles beside = attach_result_dir(dir);
    CHECK(!beside.held());
    CHECK(beside.identity() == identity);
  }

  // The same manifest (keys in any order): the same campaign, its results there, the partial file gone.
  const ResultFiles again =
      open_result_dir(dir, Manifest{"test", {{"clock", "inprocess"}, {"scenario_digest", "00aa"}}, {}});
  CHECK(!again.made());
  CHECK(again.identity() == identity);
  CHECK(again.read("seed-3") == std::optional<std::string>("three"));
  CHECK(!fs::exists(again.runs_dir() + "/seed-4.json.host.1.partial"));
  const Manifest kept = read_manifest(dir);
  CHECK(kept.campaign == "test");
  CHECK(kept.fields == manifest.fields);
  CHECK(kept.made.at("pid").get<int>() == ::getpid());
  // Its text: campaign, format, the command's keys and made, one form for every campaign.
  const nlohmann::json text = nlohmann::json::parse(slurp(dir + "/campaign.json"));
  CHECK(text.at("format") == kManifestFormat);
  CHECK(text.at("scenario_digest") == "00aa");
  CHECK(text.size() == 5);

  const std::string other = base + "/other";
  fs::create_directories(other);
  std::ofstream(other + "/notes.txt") << "mine";
  CHECK_THROWS_WITH(open_result_dir(other, manifest),
                    Catch::Contains("not empty and holds no campaign") && Catch::Contains("it holds notes.txt"));
  CHECK(slurp(other + "/notes.txt") == "mine");
  CHECK(!fs::exists(other + "/campaign.json"));
  CHECK_THROWS_WITH(again.file("../x"), Catch::Contains("'../x'"));

  // A campaign made apart with the same options is another campaign: its result files are refused,
  // named, when read and when the directory is opened; so are another item's and a stray file.
  const std::string twin = base + "/twin";
  {
    const ResultFiles t = open_result_dir(twin, manifest);
    CHECK(t.identity() != identity);
    t.write("seed-5", "five of the twin");
    t.write("seed-6", "six of the twin");
  }
  CHECK_THROWS_WITH(open_result_dir(twin, Manifest{"test", {{"scenario_digest", "00bb"}, {"clock", "inprocess"}}, {}}),
                    Catch::Contains(twin + " holds another campaign") &&
                        Catch::Contains("scenario_digest is \"00aa\"") && Catch::Contains("\"00bb\""));
  CHECK_THROWS_WITH(open_result_dir(twin, Manifest{"test", {{"scenario_digest", "00aa"}}, {}}),
                    Catch::Contains("it has clock"));
  CHECK_THROWS_WITH(open_result_dir(twin, Manifest{"power", {{"clock", "lockstep"}}, {}}),
                    Catch::Contains("its campaign is \"test\", this one's \"power\""));
  // A campaign of another rig's format is another campaign, named as such, and left as it was.
  const std::string older = base + "/older";
  fs::create_directories(older);
  std::ofstream(older + "/campaign.json") << R"({"campaign": "test", "scenario digest": "00aa", "clock": "inprocess"})";
  CHECK_THROWS_WITH(open_result_dir(older, manifest),
                    Catch::Contains(older + " holds another campaign: its format is missing") &&
                        Catch::Contains("finish it with the rig that made it"));
  CHECK_THROWS_WITH(read_manifest(older),
                    Catch::Contains("format missing, this rig reads \"" + std::string(kManifestFormat) + "\""));
  CHECK(!fs::exists(older + "/runs"));
  fs::copy_file(twin + "/runs/seed-5.json", again.runs_dir() + "/seed-5.json");
  CHECK_THROWS_AS(again.read("seed-5"), ForeignResult);
  CHECK_THROWS_WITH(again.read("seed-5"),
                    Catch::Contains(again.runs_dir() + "/seed-5.json is not a result of this campaign") &&
                        Catch::Contains("another campaign"));
  CHECK_THROWS_WITH(again.check_all(), Catch::Contains("seed-5.json"));
  fs::remove(again.runs_dir() + "/seed-5.json");
  fs::copy_file(again.runs_dir() + "/seed-3.json", again.runs_dir() + "/seed-7.json");
  CHECK_THROWS_WITH(again.read("seed-7"), Catch::Contains("it holds item seed-3, not seed-7"));
  fs::remove(again.runs_dir() + "/seed-7.json");
  std::ofstream(again.runs_dir() + "/seed-8.json") << "{\"index\": 8}\n";
  CHECK_THROWS_WITH(again.read("seed-8"), Catch::Contains("does not start with a campaign line"));
  fs::remove(again.runs_dir() + "/seed-8.json");
  std::ofstream(again.runs_dir() + "/notes.txt") << "mine";
  CHECK_THROWS_WITH(again.check_all(),
                    Catch::Contains(again.runs_dir() + "/notes.txt is not a result file of a campaign"));
  fs::remove(again.runs_dir() + "/notes.txt");
  CHECK_NOTHROW(again.check_all());
  CHECK(again.read("seed-3") == std::optional<std::string>("three"));
}

TEST_CASE(
    "result files: started again, a campaign does only the items without a kept result, and keeps what "
    "the first start finished",
    "[campaign][result_files]") {
  const std::string dir = scratch("kept");
  const ResultFiles files = open_result_dir(dir + "/c", Manifest{"test", nlohmann::json::object(), {}});
  const std::string calls = dir + "/calls.txt";  // each item done appends its index (items run in workers)
  KeptItems items;
  for (std::size_t i = 0; i < 6; ++i) items.keys.push_back("item-" + std::to_string(i));
  items.keep = [](const std::string& line) { return line.rfind("error ", 0) != 0; };
  bool fail_four = true;
  PoolWork pool;
  pool.work = [&](std::size_t i) -> std::string {
    std::ofstream(calls, std::ios::app) << i << "\n";
    if (i == 4 && fail_four) throw std::runtime_error("not this time");
    return "value " + std::to_string(i * i);
  };
  pool.died = [](std::size_t, const std::string& how) { return "error " + how; };
  std::vector<std::size_t> done_seen;
  pool.finished = [&](std::size_t, const std::string&, std::size_t done) { done_seen.push_back(done); };
  const auto called = [&] {
    std::ifstream in(calls);
    std::multiset<std::size_t> s;
    for (std::size_t i; in >> i;) s.insert(i);
    fs::remove(calls);
    return s;
  };

  const std::vector<std::string> first = run_kept(items, 2, pool, &files);
  CHECK(first[4] == "error not this time");
  CHECK(called() == std::multiset<std::size_t>{0, 1, 2, 3, 4, 5});
  CHECK(!files.has("item-4"));  // a failed item is not kept: it is done again next time
  CHECK(files.read("item-5") == std::optional<std::string>("value 25"));

  fail_four = false;
  done_seen.clear();
  items.redo = [](std::size_t i) { return i == 1; };
  const std::vector<std::string> second = run_kept(items, 2, pool, &files);
  CHECK(called() == std::multiset<std::size_t>{1, 4});
  for (std::size_t i = 0; i < 6; ++i) CHECK(second[i] == "value " + std::to_string(i * i));
  CHECK(done_seen == std::vector<std::size_t>{5, 6});  // counting the four read

  items.redo = nullptr;
  CHECK(run_kept(items, 2, pool, &files) == second);
  CHECK(called().empty());
  CHECK(run_kept(items, 2, pool, nullptr) == second);  // without a directory: every item done
  CHECK(called().size() == 6);
}
