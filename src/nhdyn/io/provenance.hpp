// Where a result came from: the provenance header that every CSV result and HTML report of a run
// carries, so that a file found later names the nhdyn that wrote it, the model (its name, file and
// a hash of its text), every parameter value as run (after --set), the initial state and the run's
// options (formulation, integrator, tolerances, evaluator, ...). In a CSV it is a block of comment
// lines ("# key: value") before the column names, which pandas (comment="#"), gnuplot and nhdyn's
// own reader (io/csv.hpp) skip; in an HTML report an HTML comment at the top of the page.
// `nhdyn report` reads it back (parameters, model hash) instead of asking for --set again.
//
//     # nhdyn version: 0.2.0 (commit 9269c4c0a1b2)
//     # model: sled
//     # model file: examples/sled.toml
//     # model hash: fnv1a64:5d0c9f0f1c2b3a49
//     # parameters: m=1, I=0.1, a=0.2, ...
//     # initial: x=0, y=0, phi=0, x'=1, y'=0, phi'=0.5
//     # run: method=sanh, complement=qr, integrator=dopri5, rtol=1e-08, ...
//     # end of provenance
//
// Values are written in the shortest form that reads back to the same double, so a parameter set
// from the header reproduces the run's value exactly.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace nhdyn {

struct Provenance {
  std::string version;     // nhdyn's version and commit, "0.2.0 (commit 9269c4c0a1b2)"
  std::string model;       // the model's name
  std::string model_file;  // the path it was read from, "built-in" or "<string>" (Python's loads)
  std::string model_hash;  // calc_text_hash of the model file's text (of "builtin:NAME" for a built-in)
  std::vector<std::pair<std::string, double>> parameters;  // every parameter, as run
  std::vector<std::pair<std::string, double>> initial;     // q by name, then q' ("phi'"), as given
  std::vector<std::pair<std::string, std::string>> run;    // option name -> value, in order
};

// "fnv1a64:" and 16 hex digits of the FNV-1a hash of `text`: enough to tell two versions of a
// model file apart (not a cryptographic hash). Same text -> same hash on every machine.
std::string calc_text_hash(std::string_view text);

// This build's "VERSION (commit COMMIT)" (core/version.hpp).
std::string nhdyn_version_text();

// The header's lines, each "# key: value\n", the last "# end of provenance\n". Names and values
// contain no newline (a newline in an option's value is written as a space).
std::string format_provenance(const Provenance& provenance);

// The provenance in the comment lines `comments` (each without its leading '#', as CsvTable keeps
// them); nullopt when they hold none (a CSV written by hand, or by nhdyn before 0.2). Throws
// InputError naming `file` and what is missing when the header is truncated (its first line
// without the rest, or a line that is not "key: value") and what to do.
std::optional<Provenance> parse_provenance(const std::vector<std::string>& comments, const std::string& file);

}  // namespace nhdyn
