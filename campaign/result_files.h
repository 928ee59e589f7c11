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
/// One writer per campaign directory: open_result_dir() takes DIR (core/output_lock.h) before
/// anything is written in it and holds it while the ResultFiles (or a copy) lives; a second
/// campaign on DIR is refused at once, naming the process that holds it. A directory is a
/// campaign's only if it is new, empty, or holds that campaign's manifest: anything else is
/// refused untouched. Each result file starts with a line naming its campaign (the digest of the
/// manifest, as written) and its item, checked whenever it is read: a file of another campaign,
/// another item or none is refused, naming it, never counted or merged.
///
/// Every campaign has the one manifest form (Manifest): whose campaign it is, the format, and
/// the command's own keys, snake_case; a file the results depend on is named by its digest
/// (`<file>_digest`).
///
/// Results go through the worker pool (worker_pool.h): run_kept() does the items that have no
/// result file yet and writes each one's as it finishes.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "campaign/worker_pool.h"

namespace nimble {
class OutputLock;
}

namespace nimble::campaign {

/// The format of the manifests this rig writes and reads. A directory whose manifest has another
/// (or none: the format of an older rig) is another campaign, refused naming both.
inline constexpr const char* kManifestFormat = "nimble-rig-campaign/3";

/// A campaign's manifest (DIR/campaign.json), the one form of every campaign's: as JSON, an
/// object with "campaign", "format", the command's keys and "made".
struct Manifest {
  /// Whose campaign it is: the command ("rig sweep", "rig reproduce thesis",
  /// "rig discrepancy --power"); compared first.
  std::string campaign;
  /// What makes two of its campaigns different, one key per thing (snake_case; a file the results
  /// depend on by its digest, "<file>_digest"); compared key by key.
  nlohmann::json fields = nlohmann::json::object();
  /// When, where and by which process the campaign was made (unix_s, host, pid): recorded, not
  /// compared; null until open_result_dir() made it.
  nlohmann::json made;
};

/// The manifest as campaign.json holds it.
void to_json(nlohmann::json& j, const Manifest& m);
/// @throws std::runtime_error naming what is wrong: not an object, no campaign, another format,
///         or "made" without its unix_s.
void from_json(const nlohmann::json& j, Manifest& m);

/// A result file that is not this campaign's: another campaign's, another item's, or no result
/// file of a campaign at all. Its message names the file and what differs.
class ForeignResult : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The manifest and result files of a campaign directory.
class ResultFiles {
 public:
  ResultFiles() = default;
  /// The files of DIR for the campaign whose identity (the digest of its manifest) is `identity`.
  ResultFiles(std::string dir, std::string identity) : dir_(std::move(dir)), identity_(std::move(identity)) {}

  const std::string& dir() const { return dir_; }
  /// The campaign's identity, which each of its result files carries: the digest of its manifest.
  const std::string& identity() const { return identity_; }
  /// open_result_dir() made the campaign now (DIR was new or empty), rather than finding it there.
  bool made() const { return made_; }
  /// This process holds DIR (open_result_dir()), as its one writer.
  bool held() const { return lock_ != nullptr; }
  std::string manifest_file() const { return dir_ + "/campaign.json"; }
  std::string runs_dir() const { return dir_ + "/runs"; }
  /// DIR/runs/<key>.json; a key is letters, digits, '.', '_' and '-'.
  std::string file(const std::string& key) const;
  /// The item has a result file (whose campaign is checked when it is read).
  bool has(const std::string& key) const;
  /// The item's result (the file's text after its campaign line, without its last line end);
  /// nullopt if it has none.
  /// @throws ForeignResult naming the file if it is another campaign's or another item's, or no
  ///         result file; std::runtime_error naming the file if it cannot be read or is cut short.
  std::optional<std::string> read(const std::string& key) const;
  /// Writes the item's result whole, after its campaign line. @throws OutputError naming the file.
  void write(const std::string& key, const std::string& text) const;
  /// Removes the temporary files that an interrupted writer left in DIR/runs.
  void remove_partial() const;
  /// Checks every file in DIR/runs: a result file of this campaign, named for its item.
  /// @throws ForeignResult naming the first that is not (a file cut short within its campaign
  ///         line is left to read(), which names it as damaged).
  void check_all() const;

 private:
  friend ResultFiles open_result_dir(const std::string& dir, const Manifest& manifest);
  std::string dir_;
  std::string identity_;
  bool made_ = false;
  std::shared_ptr<const OutputLock> lock_;
};

/// Takes DIR as the one writer of the campaign `manifest` describes (its "made", if any, is not
/// compared): a new or empty DIR gets the manifest (with "made" now) and DIR/runs; a DIR that
/// holds this manifest already is the same campaign, to be finished: its partial files are
/// removed and its result files checked. Keys are compared campaign first, then format, then the
/// command's.
/// @throws OutputBusy naming DIR and the holder's pid if another process holds it;
///         std::runtime_error naming DIR and what it holds if it is not empty and holds no
///         campaign, or the first key whose value differs if it holds another campaign (or a
///         manifest that cannot be read); ForeignResult naming a result file not of this campaign.
///         Nothing in DIR is changed when it is refused.
ResultFiles open_result_dir(const std::string& dir, const Manifest& manifest);

/// The manifest of the campaign in DIR, "made" and all.
/// @throws std::runtime_error naming the file and what is wrong if it is missing, cannot be read
///         or is not a manifest of this rig's format.
Manifest read_manifest(const std::string& dir);

/// The result files of the campaign in DIR for a process that writes results while another holds
/// DIR (an array task of a Slurm job, while `rig sweep` waits for it): nothing is taken, made or
/// removed. @throws std::runtime_error as read_manifest().
ResultFiles attach_result_dir(const std::string& dir);

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
/// pool.finished sees every item done here, with `done` counting the ones read too. With
/// pool.forget the results are returned empty (each kept result is still read, and checked).
std::vector<std::string> run_kept(const KeptItems& items, int jobs, const PoolWork& pool, const ResultFiles* files);

}  // namespace nimble::campaign
