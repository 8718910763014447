// The studies behind docs/studies/: each `nhdyn study NAME` reproduces one published table and
// plot from a single command. Every study registers itself under the `study` command through one
// of these functions, defined in its own file (study_<name>.cpp).
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "nhdyn/model/model.hpp"

namespace nhdyn::cli {

// `nhdyn study error-relation`: global error against constraint residual (docs/studies/error-relation.md).
std::function<int()> add_error_relation_study(CLI::App& study);
// `nhdyn study spread-masses`: accelerations and reactions against a 50-digit reference as the
// mass ratio grows (docs/studies/spread-masses.md).
std::function<int()> add_spread_masses_study(CLI::App& study);
// `nhdyn study tracking`: the error of program motion against the programs' residual over
// tolerances and feedback gains (docs/studies/tracking.md).
std::function<int()> add_tracking_study(CLI::App& study);

// Where a tolerance study writes its series beside its table: TABLE.csv -> TABLE-by-tolerance.csv.
std::filesystem::path by_tolerance_path(const std::filesystem::path& table);

// The exit code of a study whose table is written: 1 when some of its `runs` failed, after one
// line on stderr, with or without -q (the table marks them; the failure must show without it).
// `failures` holds each failed run's message.
int study_exit(const std::string& study, const Model& model, std::size_t runs, const std::vector<std::string>& failures);

}  // namespace nhdyn::cli
