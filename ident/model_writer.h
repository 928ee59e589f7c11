#pragma once
/// Writes a DerivativeModel as a model file in the format of
/// rig_configs/models/*.yaml, which load_model() (core/model.h) reads back.

#include <string>
#include <vector>

#include "core/model.h"

namespace nimble::ident {

/// YAML text of `model`: `comments` as `#` lines at the top, then name,
/// source, structure (and roll_yaw_coupling for lateral4), `vehicle_path` as
/// the vehicle key, inputs, trim, every derivative with its unit, and under
/// `published:` the model's eigenvalues and derivative standard deviations
/// (for an identified model: those of the identification). Numbers have 9
/// significant digits.
std::string format_model_yaml(const DerivativeModel& model, const std::string& vehicle_path,
                              const std::vector<std::string>& comments);

/// Writes format_model_yaml() to `file`, with model.vehicle_file written
/// relative to the directory of `file` (absolute if it has no relative form).
/// @throws std::runtime_error if the file cannot be written.
void write_model_yaml(const DerivativeModel& model, const std::string& file, const std::vector<std::string>& comments);

}  // namespace nimble::ident
