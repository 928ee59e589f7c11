#pragma once
/// The discrepancy workflow's parts for several flights at once (discrepancy_pool.cc): each
/// flight prepared alone, joined, its own folds and noise level, and the test that the flights
/// agree on a named effect; the rest of the workflow's parts: discrepancy_parts.h.

#include <cstddef>
#include <utility>
#include <vector>

#include "discrepancy/discrepancy_parts.h"

namespace nimble::ident::discrepancy_parts {

/// Flights prepared one by one (their own filter and derivatives) and joined end to end: the
/// signals every flight has, time running on (each flight after the last, one sample apart).
/// `rows` gets each flight's [first, last) rows. (A delayed column's first samples of a flight
/// see the end of the one before: at most delay_max_s of each.)
UniformData join_flights(const std::vector<UniformData>& flights, std::vector<std::pair<Index, Index>>& rows);

/// K contiguous folds in each flight: every fold of the pool is one block of one flight, so each
/// flight has its own held-out folds.
Folds flight_folds(const std::vector<std::pair<Index, Index>>& rows, std::size_t k);

/// Weights each flight's rows of every equation by the pool's residual level over the flight's
/// own (the baseline fit's residuals `resid`), so that a noisy flight does not outweigh a quiet one
/// (weighted least squares with each flight's own noise level); returns the levels per flight
/// and equation.
std::vector<std::vector<double>> weight_flights(Model& m, const std::vector<VectorXd>& resid,
                                                const std::vector<std::pair<Index, Index>>& rows);

/// Each flight's estimate of each named effect's parameters (the final model refit on its rows
/// alone) and the test that they are the same in all flights (Cochran's Q).
void flight_consistency(const Model& m, const BatchRule& batch, const std::vector<std::pair<Index, Index>>& rows,
                        double alpha, DiscrepancyResult& res);

}  // namespace nimble::ident::discrepancy_parts
