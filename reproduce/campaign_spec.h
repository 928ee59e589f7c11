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
  std::map<std::string, TableSpec> tables;
  std::vector<CauseSpec> causes;
};

/// The tables a campaign file must have, in the order they are printed.
const std::vector<std::string>& campaign_table_ids();

/// The flight a table is computed from, for the tables whose reasons may fly a cause
/// (validation tables); empty for the others.
std::string table_flight(const std::string& id);

/// Reads and checks a campaign file. @throws ConfigError naming the key: a wildcard or unknown
/// cell in a reason, a reason with a cause on a table that has no flight of its own, a table
/// without its category's statement.
CampaignSpec load_campaign(const std::string& file);

}  // namespace nimble::reproduce
