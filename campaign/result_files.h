#pragma once
/// The campaigns' one result model. A campaign kept in a directory holds its manifest
/// (DIR/campaign.json: what the campaign is) and one result file per finished item
/// (DIR/runs/<key>.json), each written whole (core/output_file.h's write_file: a temporary name,
/// fsync, rename), so a half-written result is never read. An interrupted campaign keeps every
/// item that finished; started again in the same directory, it does only the others.
///
///   rig sweep                       keys run-NNNNNN, one run each (campaign.h)
///   rig reproduce thesis --dir D    keys seed-N, one seed with every flight it needs
///   rig discrepancy --power --dir D keys <cell>-seed-N, one flight and its workflow verdict
///
/// Results go through the worker pool (worker_pool.h): run_kept() does the items that have no
/// result file yet and writes each one's as it finishes.

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "campaign/worker_pool.h"

namespace nimble::campaign {

/// The manifest and result files of a campaign directory.
class ResultFiles {
 public:
  explicit ResultFiles(std::string dir) : dir_(std::move(dir)) {}

  const std::string& dir() const { return dir_; }
  std::string manifest_file() const { return dir_ + "/campaign.json"; }
  std::string runs_dir() const { return dir_ + "/runs"; }
  /// DIR/runs/<key>.json; a key is letters, digits, '.', '_' and '-'.
  std::string file(const std::string& key) const;
  /// The item has a result file.
  bool has(const std::string& key) const;
  /// The item's result (the file's text without its last line end); nullopt if it has none.
  /// @throws std::runtime_error naming the file if it is there and cannot be read.
  std::optional<std::string> read(const std::string& key) const;
  /// Writes the item's result whole. @throws OutputError naming the file.
  void write(const std::string& key, const std::string& text) const;
  /// Removes the temporary files that an interrupted writer left in DIR/runs.
  void remove_partial() const;

 private:
  std::string dir_;
};

/// Opens DIR for a campaign whose manifest is `manifest` (a JSON object's text, one key per
/// thing that makes two campaigns different): a new or empty DIR gets it, with DIR/runs; a DIR
/// that holds this manifest already is the same campaign, to be finished.
/// @throws std::runtime_error naming DIR and the first key whose value differs, if DIR holds
/// another campaign (or a manifest that cannot be read).
ResultFiles open_result_dir(const std::string& dir, const std::string& manifest);

/// The items of run_kept(): item i's key, and which results are kept (an item whose result
/// says it failed is done again next time).
struct KeptItems {
  std::vector<std::string> keys;
  std::function<bool(const std::string& result)> keep;
  /// Items done again even when they have a result (optional): e.g. the one whose flights draw
  /// the figures, which only a flight that happens now can draw.
  std::function<bool(std::size_t item)> redo;
};

/// Does every item as run_in_workers() does, except that an item whose key has a result file in
/// `files` is read from it, not done, and the result of each item done is written as it
/// finishes when items.keep says so. Without `files` (nullptr) it is run_in_workers().
/// pool.finished sees every item done here, with `done` counting the ones read too.
std::vector<std::string> run_kept(const KeptItems& items, int jobs, const PoolWork& pool, const ResultFiles* files);

}  // namespace nimble::campaign
