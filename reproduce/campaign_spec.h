#pragma once
/// The campaign file of `rig reproduce thesis` as read (rig_configs/reproduce/thesis.yaml);
/// internal to reproduce/.

#include <map>
#include <string>
#include <vector>

#include "reproduce/cell_verdict.h"

namespace nimble::reproduce {

/// One closed-loop cause of the campaign file: a name, where its size comes from, the overrides.
struct CauseSpec {
  std::string name;
  std::string source;
  std::map<std::string, std::string> with;
};

struct CampaignSpec {
  std::string file;
  std::map<std::string, std::string> flights;  ///< name -> scenario
  struct Set {
    std::string row;        ///< "set N"
    std::string model;      ///< the set's model file
    std::string manoeuvre;  ///< the set's identification train (empty: the scenario's)
  };
  std::vector<Set> sets;
  std::string lateral4_model;
  std::map<std::string, std::string> coupled_models;  ///< table id -> model file
  /// Appendix E's three-state input variants: table id ("E.2", "E.3") -> the model file the
  /// identification train is flown on and re-identified with that file's inputs.
  std::map<std::string, std::string> input_variants;
  std::map<std::string, TableSpec> tables;
  std::vector<CauseSpec> causes;
};

/// The tables a campaign file must have, in the order they are printed.
const std::vector<std::string>& campaign_table_ids();

/// What a table's cells are computed from, fixed by the code that computes them
/// (reproduce/thesis_campaign.cc); the category follows from it (category_of()), so the campaign
/// file lists cells and published numbers, never their category.
enum class Source {
  kFlightRanges,       ///< 9.4: ranges of the rig's identification flights
  kReidentifiedPlant,  ///< 9.5, 9.6 (and by output error), 8.9-8.15, D, E: the rig's identification of its own plant file
  kModelArithmetic,    ///< 9.5-model, 9.6-model, 8.8, 8.9-model, 8.13-model, E.*-model: arithmetic on a model file
  kFlightFit,          ///< 4, 7-16, 8.2, 8.4, 8.7: fit metrics of a model on the rig's flights
  kFlightCorrelation,  ///< H.1-H.5: parameter correlations of the rig's identification of its flight
};

/// The tables of the plant files' derivatives that D.1's and D.2's OLS and WLS rows are judged
/// against (computed, not printed: the thesis has no such table).
inline constexpr const char* kPlantDerivativesD1 = "D.1-plant";
inline constexpr const char* kPlantDerivativesD2 = "D.2-plant";

/// The source of table `id` (one of campaign_table_ids()).
Source table_source(const std::string& id);

/// The category of a table computed from `s`: ranges and fit metrics of flights (which carry the
/// rig's sensing, estimator and effects, which the plant file does not fix) are flights; a
/// re-identification of the plant file and arithmetic on a model file are model checks.
Category category_of(Source s);

/// What a table computed from `s` shows, printed with it.
const char* source_statement(Source s);

/// The table holding the plant file's exact values that table `id`'s cells are judged against
/// (a pipeline check: "9.5" -> "9.5-model"); empty for a table judged against the published values.
std::string reference_table(const std::string& id);

/// The flight a table is computed from, for the tables whose reasons may fly a cause
/// (validation tables); empty for the others.
std::string table_flight(const std::string& id);

/// Reads and checks a campaign file. @throws ConfigError naming the key: a wildcard or unknown
/// cell in a reason, a reason with a cause on a table that has no flight of its own, a category or
/// a statement of why (the code decides both), a tolerance, sigma, tuned cells or reasons on a
/// pipeline check (its tolerance is derived).
CampaignSpec load_campaign(const std::string& file);

}  // namespace nimble::reproduce
