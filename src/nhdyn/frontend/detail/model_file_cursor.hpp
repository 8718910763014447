// The model-file loader's reader: the Cursor, through which every TOML node of a model file is
// reached by a type-checked accessor (as_string, as_table, ...) whose error is a ModelError naming
// file:line:column and what to write instead, so that no input can make the loader dereference a
// missing node; and the LoadContext, what the sections of a file share (the cursor, and what
// earlier sections found that later ones read). The sections themselves are read in
// model_file_equations.cpp and model_file_multibody.cpp (declared in model_file_sections.hpp),
// called in the order of docs/model-format.md by load_model_string (model_file.cpp).
// Internal: the model-file loader's own, not part of the public API (nhdyn/nhdyn.hpp).
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include <toml++/toml.h>

#include "nhdyn/core/error.hpp"
#include "nhdyn/model/parameters.hpp"

// Declared only: this header stays free of GiNaC (tests/layering).
namespace nhdyn::symbolic {
struct SourceLocation;
}  // namespace nhdyn::symbolic

namespace nhdyn::model_file {

using symbolic::SourceLocation;

// The keys of the top level of a model file (docs/model-format.md), in the order the doc lists
// them; the cursor names them when one is written below a section's header.
const std::vector<std::string>& top_level_keys();

// How a node's type is named in messages ("a string", "an array", ...).
std::string_view type_name(const toml::node& node);

// One key = value of a table, in the order of the file.
struct Entry {
  const toml::key* key;
  const toml::node* value;
};

// toml++ keeps a table's keys sorted by name; errors and parameters follow the file's order.
std::vector<Entry> in_file_order(const toml::table& table);

// A double as text that GiNaC's parser reads back to the same value ("0.5", "1e-05", "3").
std::string number_text(double value);

// The cursor every section of the file is read through: the text and the name of the file, where
// each line starts, and the type-checked accessors that turn a node of the wrong kind into a
// ModelError naming file:line:column and what to write instead.
class Cursor {
 public:
  Cursor(std::string_view text, std::string file);

  std::string_view text() const { return text_; }
  const std::string& file() const { return file_; }

  // ---- Locations and errors ----------------------------------------------------------------

  SourceLocation at(const toml::source_region& region) const;
  SourceLocation at(const toml::node& node) const;
  SourceLocation at(const toml::key& key) const;
  // Where a table is: its header, or for a table that has none (made implicit by [a.b] or a
  // dotted key) the key that names it.
  SourceLocation at(const toml::node& table, const toml::key& key) const;

  [[noreturn]] void fail(const SourceLocation& where, const std::string& message) const;

  // Byte offset in text_ of a 1-based (line, column), toml++ counting columns in code points.
  std::optional<std::size_t> offset_of(const toml::source_position& position) const;

  // The (line, column) of byte offset p of text_.
  SourceLocation location_of(std::size_t p) const;

  // Where byte `offset` of the content of a string value sits in the file, following the quotes,
  // escapes and line continuations of TOML's four kinds of string. Falls back to the node itself.
  SourceLocation string_position(const toml::node& node, std::size_t offset) const;

  // Where the text of a value starts: inside the quotes for a string.
  SourceLocation content_at(const toml::node& node) const;

  // Runs a SpecBuilder call that was given content_at(node) and moves the position of its error
  // to the file. SpecBuilder counts from content_at(node) through the text as TOML delivers it
  // (escapes decoded, line continuations removed); string_position follows the raw file instead.
  template <class Call>
  auto located(const toml::node& node, Call&& call) const -> decltype(call()) {
    try {
      return call();
    } catch (const ModelError& e) {
      std::optional<std::string> moved = move_into_file(node, e.what());
      if (!moved) throw;
      throw ModelError(*moved);
    }
  }

  // The message with its leading "file:line:column" replaced by the file position of the same
  // character, when that position lies inside the string value `node`; nullopt otherwise.
  std::optional<std::string> move_into_file(const toml::node& node, std::string_view message) const;

  // ---- Type-checked access -------------------------------------------------------------------

  // A top-level key found inside a section was written below that section's header: say so.
  void check_not_misplaced(const toml::key& key, std::string_view context) const;

  // Every key of `table` must be one of `allowed`; `context` says where we are ("in [plot]").
  void check_keys(const toml::table& table, const std::vector<std::string>& allowed, std::string_view context) const;

  const toml::node* required(const toml::table& root, std::string_view key, std::string_view what) const;

  const toml::table& table_of(const toml::node& node, std::string_view what, std::string_view example) const;

  const toml::array& array_of(const toml::node& node, std::string_view what, std::string_view example) const;

  std::string string_of(const toml::node& node, std::string_view what, std::string_view example) const;

  // An expression must be written as a string (in double or single quotes).
  std::string expression_string(const toml::node& node, std::string_view what, std::string_view example) const;

  // A number (integer or floating point), finite.
  std::optional<double> number_value(const toml::node& node, std::string_view what) const;

  double number_of(const toml::node& node, std::string_view what, std::string_view example) const;

  // A number or an expression string, as text for SpecBuilder (initial values, entries of D).
  std::string number_or_expression(const toml::node& node, std::string_view what, std::string_view example) const;

  // ---- Entries of the arrays of tables (the multibody sections, [visual]) --------------------

  // The tables of an array of tables such as [[frames]]; `example` shows one.
  std::vector<const toml::table*> tables_of(const toml::node& node, const std::string& key,
                                            const std::vector<std::string>& keys) const;

  const toml::node& member(const toml::table& table, const std::string& section, std::string_view key,
                           std::string_view example) const;

  std::string name_of(const toml::table& table, const std::string& section) const;

  // Three numbers or expressions, e.g. translation = ["x", "y", 0].
  std::array<std::string, 3> triple_of(const toml::node& node, const std::string& what,
                                       std::string_view example) const;

  std::optional<std::array<std::string, 3>> optional_triple(const toml::table& table, std::string_view key,
                                                            const std::string& what) const;

  std::string one_of(const toml::node& node, std::string_view what, const std::vector<std::string>& names) const;

 private:
  std::string_view text_;
  std::vector<std::size_t> line_starts_;  // byte offset of the start of each line, line 1 first
  std::string file_;
};

// What the sections share: the cursor, and what earlier sections found that later ones read.
struct LoadContext {
  LoadContext(std::string_view text, std::string file) : cursor(text, std::move(file)) {}

  Cursor cursor;
  std::vector<std::string> coordinates;  // in the order `coordinates` lists them
  std::unordered_map<std::string, int> coordinate_by_name;  // index into coordinates (first of a name)
  std::vector<Parameter> parameter_values;  // as loaded so far, in file order
  std::vector<bool> q0_written, v0_written;  // per coordinate: [initial] wrote its value, its velocity
  std::vector<std::string> quaternion_coordinates;  // the quaternion frames' components, from [[frames]]
  double t0 = 0.0;  // [initial] t0, which [simulation] t_end must follow

  // A coordinate named by a key or a string; returns its index.
  int coordinate_index(const std::string& name, const SourceLocation& where, std::string_view context) const;
};

}  // namespace nhdyn::model_file
