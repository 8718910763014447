#include "nhdyn/symbolic/derivation_archive.hpp"

#include <cstdint>
#include <cstdio>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include <cln/version.h>
#include <ginac/version.h>

#include "nhdyn/core/detail/hash.hpp"
#include "nhdyn/symbolic/detail/kind.hpp"

namespace nhdyn::symbolic {
namespace {

constexpr const char* kMagic = "nhdyn-derivation-archive 3";

// Every field as a sequence: a 1 x (1 + length) GiNaC matrix whose first entry is the length.
// A matrix, not GiNaC's lst (a linked list, whose hash the archive takes of every node by op(i),
// in quadratic time) nor exprseq (which libginac cannot read back). A matrix field is the
// sequence {rows, cols, entries by row}; an ExMatrix keeps the entries it set, as {rows, cols,
// r, c, entry, r, c, entry, ...}; an optional is a sequence of none or one.
GiNaC::ex sequence(const std::vector<GiNaC::ex>& items) {
  GiNaC::matrix m(1, static_cast<unsigned>(items.size() + 1));
  m(0, 0) = static_cast<long>(items.size());
  for (std::size_t i = 0; i < items.size(); ++i) m(0, static_cast<unsigned>(i + 1)) = items[i];
  return m;
}

GiNaC::ex pack(const GiNaC::matrix& m) {
  std::vector<GiNaC::ex> out{m.rows(), m.cols()};
  for (unsigned r = 0; r < m.rows(); ++r)
    for (unsigned c = 0; c < m.cols(); ++c) out.push_back(m(r, c));
  return sequence(out);
}

GiNaC::ex pack(const ExMatrix& m) {
  std::vector<GiNaC::ex> out{m.rows(), m.cols()};
  for (unsigned c = 0; c < m.cols(); ++c)
    for (const auto& [r, entry] : m.column(c)) {
      out.push_back(r);
      out.push_back(c);
      out.push_back(entry);
    }
  return sequence(out);
}

GiNaC::ex pack(const std::vector<GiNaC::ex>& v) { return sequence(v); }

GiNaC::ex pack(const std::optional<GiNaC::ex>& e) {
  return e ? sequence({*e}) : sequence({});
}

// Two FNV-1a hashes of `bytes` (128 bits, hex): what tells a whole archive from a damaged one.
std::string checksum(const std::string& bytes) {
  char text[33];
  std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(fnv1a(bytes, kFnvOffset)),
                static_cast<unsigned long long>(fnv1a(bytes, kFnvOtherOffset)));
  return text;
}

// Unpacking throws std::runtime_error on a shape that is not one pack() writes.
unsigned count(const GiNaC::ex& e) {
  if (!GiNaC::is_a<GiNaC::numeric>(e) || !GiNaC::ex_to<GiNaC::numeric>(e).is_nonneg_integer())
    throw std::runtime_error("a size is not a whole number");
  return static_cast<unsigned>(GiNaC::ex_to<GiNaC::numeric>(e).to_int());
}

// An entry where a scalar expression belongs (a matrix there is not one pack() writes).
const GiNaC::ex& scalar(const GiNaC::ex& e) {
  if (GiNaC::is_a<GiNaC::matrix>(e)) throw std::runtime_error("a matrix where an expression belongs");
  return e;
}

// A sequence's elements.
std::vector<GiNaC::ex> as_list(const GiNaC::ex& e) {
  if (!GiNaC::is_a<GiNaC::matrix>(e)) throw std::runtime_error("not a sequence");
  const GiNaC::matrix& m = GiNaC::ex_to<GiNaC::matrix>(e);
  if (m.rows() != 1 || m.cols() < 1 || count(m(0, 0)) + 1 != m.cols()) throw std::runtime_error("not a sequence");
  std::vector<GiNaC::ex> items;
  items.reserve(m.cols() - 1);
  for (unsigned i = 1; i < m.cols(); ++i) items.push_back(m(0, i));
  return items;
}

GiNaC::matrix unpack_matrix(const GiNaC::ex& e) {
  const std::vector<GiNaC::ex> l = as_list(e);
  if (l.size() < 2) throw std::runtime_error("a matrix without its size");
  const unsigned rows = count(l[0]), cols = count(l[1]);
  if (l.size() != 2 + static_cast<std::size_t>(rows) * cols) throw std::runtime_error("a matrix of the wrong size");
  GiNaC::matrix m(rows, cols);
  for (unsigned r = 0; r < rows; ++r)
    for (unsigned c = 0; c < cols; ++c) m(r, c) = scalar(l[2 + static_cast<std::size_t>(r) * cols + c]);
  return m;
}

ExMatrix unpack_ex_matrix(const GiNaC::ex& e) {
  const std::vector<GiNaC::ex> l = as_list(e);
  if (l.size() < 2 || (l.size() - 2) % 3 != 0) throw std::runtime_error("a sparse matrix of the wrong shape");
  ExMatrix m(count(l[0]), count(l[1]));
  for (std::size_t i = 2; i < l.size(); i += 3) {
    const unsigned r = count(l[i]), c = count(l[i + 1]);
    if (r >= m.rows() || c >= m.cols()) throw std::runtime_error("an entry outside its matrix");
    m(r, c) = scalar(l[i + 2]);
  }
  return m;
}

std::vector<GiNaC::ex> unpack_vector(const GiNaC::ex& e) {
  std::vector<GiNaC::ex> l = as_list(e);
  for (const GiNaC::ex& x : l) scalar(x);
  return l;
}

std::optional<GiNaC::ex> unpack_optional(const GiNaC::ex& e) {
  const std::vector<GiNaC::ex> l = as_list(e);
  if (l.size() > 1) throw std::runtime_error("an optional of more than one");
  return l.size() == 1 ? std::optional<GiNaC::ex>(scalar(l[0])) : std::nullopt;
}

// The names of the symbols in `e`, each shared subexpression visited once.
using Seen = std::unordered_set<GiNaC::ex, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

void collect_symbols(const GiNaC::ex& e, Seen& seen, std::set<std::string>& names) {
  if (e.nops() > 0 && !seen.insert(e).second) return;
  if (GiNaC::is_a<GiNaC::symbol>(e)) {
    names.insert(GiNaC::ex_to<GiNaC::symbol>(e).get_name());
    return;
  }
  for (std::size_t i = 0; i < e.nops(); ++i) collect_symbols(e.op(i), seen, names);
}

// The fields in one order, as (name, packed expression).
std::vector<std::pair<const char*, GiNaC::ex>> fields(const Derivation& d) {
  return {{"A", pack(d.A)},
          {"Q", pack(d.Q)},
          {"G", pack(d.G)},
          {"b", pack(d.b)},
          {"b0", pack(d.b0)},
          {"D", d.D ? sequence({pack(*d.D)}) : sequence({})},
          {"phi", pack(d.phi)},
          {"f", pack(d.f)},
          {"b_p", pack(d.b_p)},
          {"b_p0", pack(d.b_p0)},
          {"B", pack(d.B)},
          {"phi_p", pack(d.phi_p)},
          {"f_p", pack(d.f_p)},
          {"energy", pack(d.energy)},
          {"energy_function", pack(d.energy_function)},
          {"power_forces", d.power_forces},
          {"power_time", d.power_time},
          {"conservative", GiNaC::numeric(d.conservative ? 1 : 0)}};
}

// The shared subexpressions of a derivation written once each. GiNaC's archive_ex stores every
// distinct subexpression once, but it walks the expression as a tree, visiting a subexpression
// at each of its uses before it finds it stored: the bicycle's derivation, 3000 distinct nodes,
// is a tree of 300 000, and archiving it took longer than deriving it. So every subexpression
// used more than once becomes a definition, wild(i) in the expressions that use it (a wildcard:
// a placeholder that archives as a number and cannot be a model's symbol), and the archive holds
// the definitions, each over the wildcards of earlier ones, then the fields over them all. Reading
// substitutes them back in order (SubstituteShared): GiNaC evaluates each rebuilt node, which gives
// the node it was, since the derivation's expressions are evaluated already; archive_derivation
// checks that on the expressions it writes, and stores nothing if one came back otherwise.
using ExMap = std::unordered_map<GiNaC::ex, GiNaC::ex, std::hash<GiNaC::ex>, GiNaC::ex_is_equal>;

class SharedSubexpressions {
 public:
  // Counts the uses of every subexpression under `e` (a use per parent, each node's children
  // counted at its first use only).
  void count_uses(const GiNaC::ex& e) {
    if (e.nops() == 0) return;
    auto [it, first] = uses_.try_emplace(e, 0u);
    ++it->second;
    if (!first) return;
    for (std::size_t i = 0; i < e.nops(); ++i) count_uses(e.op(i));
  }

  // `e` with every subexpression used more than once replaced by its wildcard, its definition
  // (over the wildcards of its own shared parts) appended to definitions().
  GiNaC::ex factor(const GiNaC::ex& e) {
    if (e.nops() == 0) return e;
    if (const auto it = factored_.find(e); it != factored_.end()) return it->second;
    struct Factor : GiNaC::map_function {
      SharedSubexpressions& self;
      explicit Factor(SharedSubexpressions& s) : self(s) {}
      GiNaC::ex operator()(const GiNaC::ex& x) override { return self.factor(x); }
    } factor_children(*this);
    GiNaC::ex out = e.map(factor_children);
    // A sequence or a matrix stays itself: it is a field's shape, not an expression.
    if (uses_[e] > 1 && !GiNaC::is_a<GiNaC::matrix>(e)) {
      definitions_.push_back(out);
      out = GiNaC::wild(static_cast<unsigned>(definitions_.size() - 1));
    }
    factored_.emplace(e, out);
    return out;
  }

  const std::vector<GiNaC::ex>& definitions() const { return definitions_; }

 private:
  std::unordered_map<GiNaC::ex, unsigned, std::hash<GiNaC::ex>, GiNaC::ex_is_equal> uses_;
  ExMap factored_;
  std::vector<GiNaC::ex> definitions_;
};

// What reading trusts of an archive, whose bytes may have been made on purpose (the checksum is
// against damage, not against a forger): a model file nests at most 256 levels (spec_builder.cpp)
// and the derivations of the examples are 6 to 20 deep, with entries of up to 50 000 nodes
// counted as a tree (the bicycle's); deeper or larger ones, which would take the compiler's
// recursion past its stack or GiNaC's tree walks (its return_type follows a product's every
// factor) into hours, are refused and derived again.
constexpr unsigned kMaxDepth = 1024;
constexpr double kMaxTreeSize = 1e7;

// The depth and the size counted as a tree (each use of a shared part again) of an expression.
struct Shape {
  unsigned depth = 0;
  double tree_size = 0.0;
};

// `e` (as written: its shared parts wildcards, a tree without repeated parts) with each wildcard
// replaced by the value of its label in `values`, every node rebuilt by GiNaC (map evaluates
// it); shape() is then that of the result, from the shapes of the values. Throws
// std::runtime_error for a wildcard of label values.size() or more, for a matrix below a node
// that is not one (a field is a sequence of sequences, whose entries are scalar expressions), and
// for an expression deeper or larger than kMaxDepth, kMaxTreeSize.
class SubstituteShared final : public GiNaC::map_function {
 public:
  SubstituteShared(const std::vector<GiNaC::ex>& values, const std::vector<Shape>& shapes)
      : values_(values), shapes_(shapes) {}

  GiNaC::ex substitute(const GiNaC::ex& e) {
    Shape top;
    children_ = &top;
    const GiNaC::ex out = (*this)(e);
    children_ = nullptr;
    shape_ = top;
    return out;
  }
  const Shape& shape() const { return shape_; }

  GiNaC::ex operator()(const GiNaC::ex& e) override {
    Shape shape;
    GiNaC::ex out = e;
    // A node's class by one look-up (detail/kind.hpp); matrices and wildcards are among the others.
    const bool other = detail::kind_of(e) == detail::ExKind::other;
    const bool matrix = other && e.nops() > 0 && GiNaC::is_a<GiNaC::matrix>(e);
    if (e.nops() > 0) {
      if (matrix && scalars_above_ > 0) throw std::runtime_error("a matrix inside an expression");
      Shape* const parent = children_;
      children_ = &shape;  // the children's calls fold their shapes into this one
      if (!matrix) ++scalars_above_;
      out = e.map(*this);
      if (!matrix) --scalars_above_;
      children_ = parent;
      shape.depth += 1;
      shape.tree_size += 1.0;
    } else if (other && GiNaC::is_a<GiNaC::wildcard>(e)) {
      const unsigned label = GiNaC::ex_to<GiNaC::wildcard>(e).get_label();
      if (label >= values_.size()) throw std::runtime_error("a wildcard without its definition");
      out = values_[label];
      shape = shapes_[label];
    } else {
      shape = {1, 1.0};
    }
    // The size of a scalar expression: a field's sequences hold all its entries.
    if (shape.depth > kMaxDepth || (!matrix && !(shape.tree_size <= kMaxTreeSize)))
      throw std::runtime_error("an expression deeper or larger than a derivation makes");
    if (children_ != nullptr) {
      children_->depth = std::max(children_->depth, shape.depth);
      children_->tree_size += shape.tree_size;
    }
    return out;
  }

 private:
  const std::vector<GiNaC::ex>& values_;
  const std::vector<Shape>& shapes_;
  Shape* children_ = nullptr;
  Shape shape_;
  int scalars_above_ = 0;  // nodes above the current one that are not matrices
};

// The values of the wildcards of `definitions` and their shapes, each over earlier ones only
// (throws std::runtime_error on one that uses a later one, on one that is or holds a matrix, and
// as SubstituteShared).
struct Expanded {
  std::vector<GiNaC::ex> values;
  std::vector<Shape> shapes;
};

Expanded expand_shared(const std::vector<GiNaC::ex>& definitions) {
  Expanded out;
  out.values.reserve(definitions.size());
  out.shapes.reserve(definitions.size());
  SubstituteShared substitute(out.values, out.shapes);
  for (const GiNaC::ex& definition : definitions) {
    if (GiNaC::is_a<GiNaC::matrix>(definition)) throw std::runtime_error("a definition that is a matrix");
    out.values.push_back(substitute.substitute(definition));
    out.shapes.push_back(substitute.shape());
  }
  return out;
}

GiNaC::ex substitute_shared(const GiNaC::ex& e, const Expanded& shared) {
  SubstituteShared substitute(shared.values, shared.shapes);
  return substitute.substitute(e);
}

// Whether GiNaC can read `archive` back: its reader recurses through the nodes, so a graph deeper
// than a written derivation is (its shared parts stand for themselves: a few levels over the
// expressions' own) would take it past its stack, and a cycle, which no writer makes, forever.
// Walked here with a stack of our own, each node once.
bool within_reach(const GiNaC::archive& archive) {
  constexpr unsigned kMaxNodeDepth = kMaxDepth + 8;  // the sequences holding a field's entries
  std::unordered_map<const GiNaC::archive_node*, unsigned> depth;  // 0 while being walked
  GiNaC::archive_node::propinfovector properties;
  struct Visit {
    const GiNaC::archive_node* node;
    std::vector<const GiNaC::archive_node*> children;
    std::size_t next = 0;
    unsigned deepest = 0;
  };
  std::vector<Visit> path;
  const auto enter = [&](const GiNaC::archive_node& node) {
    if (path.size() >= kMaxNodeDepth) return false;
    depth.emplace(&node, 0u);
    Visit visit{&node, {}};
    node.get_properties(properties);
    for (const auto& p : properties)
      if (p.type == GiNaC::archive_node::PTYPE_NODE)
        for (unsigned i = 0; i < p.count; ++i) visit.children.push_back(&node.find_ex_node(p.name, i));
    path.push_back(std::move(visit));
    return true;
  };
  for (unsigned e = 0; e < archive.num_expressions(); ++e) {
    const GiNaC::archive_node& top = archive.get_top_node(e);
    if (depth.count(&top) != 0) continue;
    if (!enter(top)) return false;
    while (!path.empty()) {
      Visit& visit = path.back();
      if (visit.next < visit.children.size()) {
        const GiNaC::archive_node* child = visit.children[visit.next++];
        if (const auto it = depth.find(child); it != depth.end()) {
          if (it->second == 0) return false;  // on the path: a cycle
          visit.deepest = std::max(visit.deepest, it->second);
        } else if (!enter(*child)) {
          return false;
        }
        continue;
      }
      const unsigned mine = visit.deepest + 1;  // the longest path below and through this node
      if (mine > kMaxNodeDepth) return false;
      depth[visit.node] = mine;
      path.pop_back();
      if (!path.empty()) path.back().deepest = std::max(path.back().deepest, mine);
    }
  }
  return true;
}

// The archive of `fields` over the definitions `shared`.
std::string archive_body(const std::vector<std::pair<const char*, GiNaC::ex>>& fields,
                         const std::vector<GiNaC::ex>& shared, const std::set<std::string>& names) {
  GiNaC::archive archive;
  archive.archive_ex(sequence(shared), "shared");
  for (const auto& [name, e] : fields) archive.archive_ex(e, name);
  std::ostringstream body;
  body << names.size() << '\n';
  for (const std::string& name : names) body << name << '\n';
  body << archive;
  return body.str();
}

}  // namespace

std::string archive_derivation(const Derivation& derivation) {
  const std::vector<std::pair<const char*, GiNaC::ex>> whole = fields(derivation);
  Seen seen;
  std::set<std::string> names;
  SharedSubexpressions shared;
  for (const auto& [name, e] : whole) {
    collect_symbols(e, seen, names);
    shared.count_uses(e);
  }
  std::vector<std::pair<const char*, GiNaC::ex>> factored;
  for (const auto& [name, e] : whole) factored.emplace_back(name, shared.factor(e));
  // Reading must give every field as it is (see SharedSubexpressions), within the limits reading
  // keeps to; a derivation that would not is not stored.
  try {
    const Expanded values = expand_shared(shared.definitions());
    for (std::size_t i = 0; i < whole.size(); ++i)
      if (!substitute_shared(factored[i].second, values).is_equal(whole[i].second)) return {};
  } catch (const std::runtime_error&) {
    return {};
  }
  const std::string body = archive_body(factored, shared.definitions(), names);
  return std::string(kMagic) + "\n" + checksum(body) + "\n" + body;
}

std::string derivation_engine() {
  return "GiNaC " + std::to_string(GiNaC::version_major) + "." + std::to_string(GiNaC::version_minor) + "." +
         std::to_string(GiNaC::version_micro) + ", CLN " + std::to_string(cln::version_major) + "." +
         std::to_string(cln::version_minor) + "." + std::to_string(cln::version_patchlevel);
}

std::optional<Derivation> unarchive_derivation(const std::string& bytes, const Spec& spec) {
  const SymbolTable& symbols = spec.symbols;
  try {
    // GiNaC's reader trusts its input (a count altered in a damaged file can make it read on
    // forever), so the bytes are checked whole before it sees them.
    const std::string magic = std::string(kMagic) + "\n";
    if (bytes.compare(0, magic.size(), magic) != 0) return std::nullopt;
    const std::size_t end = bytes.find('\n', magic.size());
    if (end == std::string::npos) return std::nullopt;
    const std::string body = bytes.substr(end + 1);
    if (bytes.compare(magic.size(), end - magic.size(), checksum(body)) != 0) return std::nullopt;
    std::istringstream in(body);
    std::string line;
    std::size_t named = 0;
    if (!(in >> named) || !std::getline(in, line) || !line.empty() || named > bytes.size()) return std::nullopt;
    GiNaC::lst known;
    for (std::size_t i = 0; i < named; ++i) {
      if (!std::getline(in, line)) return std::nullopt;
      const std::optional<GiNaC::symbol> s = symbols.find(line);
      if (!s) return std::nullopt;  // a symbol of another model: reading would make a new one
      known.append(*s);
    }
    GiNaC::archive archive;
    in >> archive;
    if (!in || !within_reach(archive)) return std::nullopt;
    const Expanded values = expand_shared(as_list(archive.unarchive_ex(known, "shared")));
    const auto read = [&](const char* name) { return substitute_shared(archive.unarchive_ex(known, name), values); };
    Derivation d;
    d.A = unpack_ex_matrix(read("A"));
    d.Q = unpack_matrix(read("Q"));
    d.G = unpack_matrix(read("G"));
    d.b = unpack_ex_matrix(read("b"));
    d.b0 = unpack_matrix(read("b0"));
    if (const std::vector<GiNaC::ex> D = as_list(read("D")); D.size() == 1) d.D = unpack_matrix(D[0]);
    d.phi = unpack_vector(read("phi"));
    d.f = unpack_vector(read("f"));
    d.b_p = unpack_matrix(read("b_p"));
    d.b_p0 = unpack_matrix(read("b_p0"));
    d.B = unpack_matrix(read("B"));
    d.phi_p = unpack_vector(read("phi_p"));
    d.f_p = unpack_vector(read("f_p"));
    d.energy = unpack_optional(read("energy"));
    d.energy_function = unpack_optional(read("energy_function"));
    d.power_forces = scalar(read("power_forces"));
    d.power_time = scalar(read("power_time"));
    d.conservative = !read("conservative").is_zero();
    const auto n = static_cast<unsigned>(spec.n()), s = static_cast<unsigned>(spec.s()),
               m = static_cast<unsigned>(spec.m());
    const auto sized = [](const GiNaC::matrix& x, unsigned rows, unsigned cols) {
      return x.rows() == rows && x.cols() == cols;
    };
    if (d.A.rows() != n || d.A.cols() != n || d.b.rows() != s || d.b.cols() != n || !sized(d.Q, n, 1) ||
        !sized(d.G, n, 1) || !sized(d.b0, s, 1) || (d.D && d.D->cols() != n) || d.b_p.rows() != m ||
        (m > 0 && d.b_p.cols() != n) || d.b_p0.rows() != m || d.B.cols() != m || (m > 0 && d.B.rows() != n))
      return std::nullopt;  // made for a model of other sizes
    return d;
  } catch (const std::exception&) {
    return std::nullopt;  // not an archive GiNaC reads, or not of this shape
  }
}

}  // namespace nhdyn::symbolic
