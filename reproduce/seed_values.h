#pragma once
/// What one seed of `rig reproduce thesis` gives: the values of every table's cells on its
/// flights, the derivatives it identified, its flights' records, and the values of every flight
/// flown with a cause. Each seed is one item of the campaigns' worker pool
/// (campaign/worker_pool.h): a worker flies it and hands it over as one line of JSON, which reads
/// back exactly (doubles to the bit, NaN included), so the tables come out the same whether the
/// seeds flew in one process or in several.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "campaign/result_files.h"
#include "reproduce/thesis_campaign.h"

namespace nimble::reproduce {

/// The values of one table's cells on one seed: "row / column" -> value.
using CellMap = std::map<std::string, double>;

/// One flight flown with a cause on this seed: its table's values, why it did not fly as its
/// scenario asks (empty if it did), and its record if this item flew it (a flight two items share
/// is flown once).
struct WithFlight {
  CellMap cells;
  std::string failure;
  std::optional<FlightRecord> record;
};

struct SeedValues {
  std::uint64_t seed = 1;
  std::map<std::string, CellMap> tables;                            ///< table id -> its cells
  std::map<std::string, std::map<std::string, double>> identified;  ///< set row -> derivative -> value
  std::map<std::string, std::map<std::string, double>> plant;       ///< set row -> derivative -> the plant's
  std::vector<FlightRecord> flights;                                ///< the seed's own flights, in flying order
  std::vector<WithFlight> with;  ///< one per flight with a cause, in the plan's order
};

/// The derivatives whose identification is checked against the plant's (SeedValues::identified).
inline constexpr const char* kCheckedDerivatives[] = {"Lp", "Lv", "Yp", "Yv", "L_df", "Y_df"};
/// The key of a derivative identified by output error among a seed's identified values.
inline constexpr const char* kOutputErrorSuffix = " (output error)";
/// The key of a derivative's own standard deviation (coloured residuals) among them.
inline constexpr const char* kOwnSigmaSuffix = " sigma";

/// One line of JSON.
std::string seed_values_line(const SeedValues& values);

/// Reads seed_values_line()'s output. @throws std::runtime_error naming what is wrong.
SeedValues seed_values_from_line(const std::string& line);

struct CampaignSpec;

/// The identified derivatives against the plant's, over the seeds flown.
std::vector<PlantCheck> plant_check(const CampaignSpec& spec, const std::vector<SeedValues>& seeds);

/// A seed's key among a campaign directory's result files (campaign/result_files.h): seed-N.
std::string seed_key(std::uint64_t seed);

/// The manifest of `rig reproduce thesis --dir`: what makes a seed's values the same in two
/// campaigns, so that a directory's stored seeds are only used by the campaign that flew them.
/// The campaign file, every scenario it flies (scenario_digest: the file and all it names), every
/// model it reads and the controller copy, by content; the clock, the states, the logs'
/// directory (the records point there); the rig's executable, by content; and the overrides on
/// every flight (CampaignOptions::overrides), named (an empty list without) and inside each
/// scenario's digest. The seeds are not in it: a campaign with more seeds flies only the new ones.
campaign::Manifest seeds_manifest(const CampaignOptions& options, const CampaignSpec& spec);

}  // namespace nimble::reproduce
