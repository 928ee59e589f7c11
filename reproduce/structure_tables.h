#pragma once
/// The thesis's comparison of model structures (chapter 8, Appendices D, E and H) computed from the
/// rig's flights for `rig reproduce thesis`; internal to reproduce/.
///
/// The rig's plant flies one grey-box model per flight, so every structure identified from a
/// flight is judged as the thesis's identification would be on a vehicle that is that model:
///  - fit metrics of a structure on the flight (8.2, 8.4 four-state grey- and black-box on the
///    four-state flight; 8.7 three-state black-box on set 1's identification flight) and the
///    parameter correlations of the grey-box identifications (H.1-H.5) are the flights' own;
///  - eigenvalues, eigenvectors and derivatives of a re-identification (8.9-8.15, D.1, D.2, E.2,
///    E.3) are pipeline checks against the plant file's, the black-box models' too (a black-box
///    fit of a grey-box plant has the plant's modes);
///  - the eigenvectors of the model files (8.9-model, 8.13-model) and the input variants' files
///    (E.2-model, E.3-model) are transcription checks against the thesis.
/// Eigenvectors are the thesis's (Eq 8.8, core/modes.h): non-dimensional, normalised on the roll
/// angle, magnitude and phase; the roll angle's row (1 at 0 deg by construction) is left out.
/// The three-state tables use the thesis's inputs for them (delta_f and delta_t, Section 8.3.2);
/// the four-state ones every input the flight excites (the rig's four-state flight leaves the
/// dihedral delta_d still: its pitch loop is not part of the lateral plant).

#include <map>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/modes.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/identify.h"
#include "reproduce/campaign_spec.h"
#include "reproduce/seed_values.h"

namespace nimble::reproduce {

/// The campaign's identification of one flight as the thesis's (WLS, Eq 21 with w0 the flight's
/// initial w), plus the regressors p (w - w0) and g (sin phi - phi) in the side-force equation
/// (the part of the exact kinematics Eq 21 linearises; their coefficients are reported, not part
/// of the model). `options` gives the structure, method, inputs and the rest of the trim.
ident::IdentResult identify_as_thesis(const ident::FlightData& data, const Vehicle& vehicle,
                                      const std::string& vehicle_file, const std::string& name,
                                      ident::IdentOptions options = {});

/// A fit's metrics: "<row> / rxy", "<row> / R2", "<row> / RMSE %".
void put_fit(CellMap& m, const std::string& row, const ident::FitMetrics& f);

/// The fit of output `output` ("p_dot", "v_dot_star", ...). @throws std::runtime_error if none.
const ident::OutputFit& fit_of(const std::vector<ident::OutputFit>& fits, const std::string& output);

/// A three-state model's eigenvalues: "<row> / aperiodic", "<row> / oscillatory re|im".
void put_eigenvalues(CellMap& m, const std::string& row, const std::vector<std::complex<double>>& eig);

/// A four-state model's eigenvalues as Table 8.8: "<row> / aperiodic stable|unstable",
/// "<row> / oscillatory re|im".
void put_eigenvalues4(CellMap& m, const std::string& row, const std::vector<std::complex<double>>& eig);

/// Non-dimensional eigenvectors as Tables 8.9-8.15: for each mode k (1-based, in order of the
/// eigenvalue's real part) and each state s but the roll angle, "s+ / mode k": an oscillatory
/// mode's magnitude, with "s+ / mode k phase" its phase [deg, in (-180, 180]]; a real mode's signed
/// component (the thesis's phase of 0 or 180 deg is its sign: a phase of zero is no number to be
/// judged relative to).
void put_eigenvectors(CellMap& m, const StateSpace& ss, const std::vector<Mode>& modes);

/// |rho| of the parameters of equation `equation` ("L", "N", "Y") of `r`: "<a> / <b>" and
/// "<b> / <a>" for each pair of distinct parameters.
void put_correlations(CellMap& m, const ident::IdentResult& r, const std::string& equation);

/// The tables from set 1's identification flight beyond Tables 9.4-9.6 and 4: 8.7, 8.13, 8.14,
/// 8.15, D.2, H.4, H.5. `set1` is the campaign's identification of it (Table 9.5's).
std::map<std::string, CellMap> three_state_tables(const ident::FlightData& measured, const ident::IdentResult& set1);

/// The tables from the four-state flight (flown on `plant`): four_state_table_ids().
std::map<std::string, CellMap> four_state_tables(const ident::FlightData& measured, const DerivativeModel& plant);

/// 8.2, 8.4, 8.9, 8.10, 8.11, D.1, H.1, H.2, H.3.
const std::vector<std::string>& four_state_table_ids();

/// Table E.2 or E.3: the flight flown on the input variant `plant` identified with its inputs.
CellMap input_variant_table(const ident::FlightData& measured, const DerivativeModel& plant);

/// The tables of arithmetic on model files the structure tables need: 8.9-model (the four-state
/// file), 8.13-model (set 1's), E.2-model, E.3-model, and the plant derivatives D.1 and D.2 are
/// judged against (kPlantDerivativesD1, kPlantDerivativesD2: rows OLS and WLS alike).
std::map<std::string, CellMap> structure_model_tables(const CampaignSpec& spec);

}  // namespace nimble::reproduce
