// Model files: a mechanical system written in TOML the way it stands in a paper — coordinates,
// parameters, kinetic and potential energy, forces, constraints at position, velocity or
// acceleration level, independent coordinates or an analytic D, initial state, simulation and plot
// defaults (docs/model-format.md). The loader only translates TOML into SpecBuilder calls
// (symbolic/spec_builder.hpp), each with the file, line and column of its TOML node; the resulting
// Spec goes on to derive() and compile_model() (symbolic/compile.hpp) like one built in C++.
//
//     model file --load_model_file--> Spec --compile_model--> Model --make_data--> Data
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "nhdyn/symbolic/spec.hpp"

namespace nhdyn {

// Reads and loads a model file. Throws FileError when the file cannot be read (missing, a
// directory, no permission) and ModelError for anything wrong inside it; every message starts with
// "file:line:column: " and says what to change. Unknown keys are errors that name the nearest
// valid key.
symbolic::Spec load_model_file(const std::filesystem::path& path);

// The text of a model file, with the FileErrors of load_model_file.
std::string read_model_text(const std::filesystem::path& path);

// The same for the text of a model file; `file_name` is used in the messages only.
symbolic::Spec load_model_string(std::string_view text, std::string file_name);

}  // namespace nhdyn
