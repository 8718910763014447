// The derivation kept between processes (symbolic/derivation_archive.hpp,
// frontend/detail/derivation_cache.hpp): a derivation read back equals the one derived, entry by
// entry, and compiles to a model that computes the same numbers to the bit; bytes of another model
// or damaged bytes are refused; the cache file is used on the second load of the same text and
// --set values, not on another, and is replaced when it does not read back.
#include <gtest/gtest.h>

#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <iterator>
#include <string>

#include "nhdyn/core/detail/hash.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/frontend/detail/derivation_cache.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/description.hpp"
#include "nhdyn/symbolic/derivation_archive.hpp"
#include "support/text.hpp"

namespace nhdyn {
namespace {

namespace fs = std::filesystem;
using symbolic::Derivation;

void expect_same(const GiNaC::matrix& a, const GiNaC::matrix& b, const std::string& what) {
  ASSERT_EQ(a.rows(), b.rows()) << what;
  ASSERT_EQ(a.cols(), b.cols()) << what;
  for (unsigned r = 0; r < a.rows(); ++r)
    for (unsigned c = 0; c < a.cols(); ++c) EXPECT_TRUE(a(r, c).is_equal(b(r, c))) << what << "(" << r << ", " << c << ")";
}

void expect_same(const std::vector<GiNaC::ex>& a, const std::vector<GiNaC::ex>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(a[i].is_equal(b[i])) << what << "[" << i << "]";
}

// The numbers a model computes at its start: q'' and the reactions.
std::vector<double> start_numbers(const Model& model) {
  Data data = make_data(model);
  EXPECT_EQ(compute_dynamics(model, data, {}, model.t0, model.q0.data(), model.v0.data()), Status::ok) << model.name;
  std::vector<double> out(data.qdd.data(), data.qdd.data() + data.qdd.size());
  out.insert(out.end(), data.R.data(), data.R.data() + data.R.size());
  return out;
}

TEST(DerivationArchive, ReadsBackEveryEntryAndComputesTheSameNumbers) {
  // Models whose derivations share many subexpressions (written once each, archive_derivation)
  // and models with none to speak of.
  for (const char* file : {"whipple_bicycle.toml", "rattleback.toml", "ball_in_bowl.toml", "sled.toml",
                           "bicycle_roll_program.toml", "ball_off_sphere_onto_floor.toml",
                           "rattleback_quaternion.toml", "tippe_top.toml", "tumbling_body.toml"}) {
    SCOPED_TRACE(file);
    const symbolic::Spec spec = load_model_file(test::example(file));
    const Derivation d = symbolic::derive(spec);
    const std::optional<Derivation> back = symbolic::unarchive_derivation(symbolic::archive_derivation(d), spec);
    ASSERT_TRUE(back.has_value());
    expect_same(d.A.dense(), back->A.dense(), "A");
    expect_same(d.b.dense(), back->b.dense(), "b");
    for (unsigned c = 0; c < d.A.cols(); ++c) EXPECT_EQ(d.A.column(c).size(), back->A.column(c).size());
    expect_same(d.Q, back->Q, "Q");
    expect_same(d.G, back->G, "G");
    expect_same(d.b0, back->b0, "b0");
    expect_same(d.b_p, back->b_p, "b_p");
    expect_same(d.b_p0, back->b_p0, "b_p0");
    expect_same(d.B, back->B, "B");
    expect_same(d.phi, back->phi, "phi");
    expect_same(d.f, back->f, "f");
    expect_same(d.phi_p, back->phi_p, "phi_p");
    expect_same(d.f_p, back->f_p, "f_p");
    EXPECT_EQ(d.D.has_value(), back->D.has_value());
    ASSERT_EQ(d.energy.has_value(), back->energy.has_value());
    if (d.energy) {
      EXPECT_TRUE(d.energy->is_equal(*back->energy));
    }
    EXPECT_EQ(d.energy_function.has_value(), back->energy_function.has_value());
    EXPECT_TRUE(d.power_forces.is_equal(back->power_forces));
    EXPECT_TRUE(d.power_time.is_equal(back->power_time));
    EXPECT_EQ(d.conservative, back->conservative);
    // The same tapes: the same numbers to the bit.
    EXPECT_EQ(start_numbers(symbolic::compile_model(spec, d)), start_numbers(symbolic::compile_model(spec, *back)));
  }
}

// A derivation beyond what reading accepts is not stored at all (archive_derivation gives no
// bytes): 1200 levels of nesting ((... (x + 1)^3 + 1)^3 ...), and a product whose factors share
// one part, doubling 24 times (2^24 nodes counted as a tree, 48 distinct ones; GiNaC itself
// walks such a product as a tree when it makes it, so the test keeps it near the limit of ten
// million).
TEST(DerivationArchive, StoresNothingBeyondWhatReadingAccepts) {
  const symbolic::Spec spec = load_model_file(test::example("sled.toml"));
  const Derivation made = symbolic::derive(spec);
  ASSERT_FALSE(symbolic::archive_derivation(made).empty());
  const GiNaC::symbol& x = spec.symbols.find("x").value();
  Derivation deep = made;
  GiNaC::ex nested = x;
  for (int i = 0; i < 600; ++i) nested = GiNaC::pow(nested + 1, 3);
  deep.Q(0, 0) = nested;
  EXPECT_TRUE(symbolic::archive_derivation(deep).empty());
  Derivation wide = made;
  GiNaC::ex doubled = x;
  for (int i = 0; i < 24; ++i) doubled = GiNaC::sin(doubled) * GiNaC::cos(doubled);
  wide.Q(0, 0) = doubled;
  EXPECT_TRUE(symbolic::archive_derivation(wide).empty());
}

// Bytes made on purpose to pass the checksum (the archive of the sled's derivation with one part
// forged, its checksum computed again as archive_derivation does): each holds what the writer
// never makes, and reading refuses it, where before a nested chain crashed the compiler and a
// doubling product hung GiNaC.
std::string forged(const symbolic::Spec& spec, const std::function<void(GiNaC::matrix& shared,
                                                                         std::map<std::string, GiNaC::ex>& fields)>& change) {
  const std::string bytes = symbolic::archive_derivation(symbolic::derive(spec));
  std::istringstream in(bytes);
  std::string magic, sum, line;
  std::getline(in, magic);
  std::getline(in, sum);
  std::size_t named = 0;
  in >> named;
  std::getline(in, line);
  std::vector<std::string> names(named);
  GiNaC::lst known;
  for (std::string& name : names) {
    std::getline(in, name);
    known.append(spec.symbols.find(name).value());
  }
  GiNaC::archive archive;
  in >> archive;
  GiNaC::matrix shared = GiNaC::ex_to<GiNaC::matrix>(archive.unarchive_ex(known, "shared"));
  std::vector<std::string> order;
  std::map<std::string, GiNaC::ex> fields;
  for (unsigned i = 1; i < archive.num_expressions(); ++i) {
    std::string name;
    const GiNaC::ex e = archive.unarchive_ex(known, name, i);
    order.push_back(name);
    fields[name] = e;
  }
  change(shared, fields);
  GiNaC::archive out;
  out.archive_ex(shared, "shared");
  for (const std::string& name : order) out.archive_ex(fields[name], name.c_str());
  std::ostringstream body;
  body << names.size() << '\n';
  for (const std::string& name : names) body << name << '\n';
  body << out;
  char text[33];
  std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(fnv1a(body.str(), kFnvOffset)),
                static_cast<unsigned long long>(fnv1a(body.str(), kFnvOtherOffset)));
  return magic + "\n" + text + "\n" + body.str();
}

// The shared definitions {count, d0, d1, ...} with `more` appended.
GiNaC::matrix with_definitions(const GiNaC::matrix& shared, const std::vector<GiNaC::ex>& more) {
  GiNaC::matrix out(1, shared.cols() + static_cast<unsigned>(more.size()));
  for (unsigned c = 1; c < shared.cols(); ++c) out(0, c) = shared(0, c);
  for (std::size_t i = 0; i < more.size(); ++i) out(0, shared.cols() + static_cast<unsigned>(i)) = more[i];
  out(0, 0) = static_cast<long>(out.cols() - 1);
  return out;
}

TEST(DerivationArchive, RefusesBytesMadeToPassItsChecksum) {
  const symbolic::Spec spec = load_model_file(test::example("sled.toml"));
  const GiNaC::symbol x = spec.symbols.find("x").value();
  // Unchanged, the bytes read back (the forging itself is sound).
  EXPECT_TRUE(symbolic::unarchive_derivation(forged(spec, [](auto&, auto&) {}), spec).has_value());
  const auto defined = [&](const GiNaC::matrix& shared) { return static_cast<unsigned>(shared.cols() - 1); };
  // A definition that uses itself, and one that uses a later one.
  EXPECT_FALSE(symbolic::unarchive_derivation(forged(spec, [&](GiNaC::matrix& shared, auto& fields) {
    const unsigned k = defined(shared);
    shared = with_definitions(shared, {GiNaC::sin(GiNaC::wild(k)) + x});
    fields["power_time"] = GiNaC::wild(k);
  }), spec).has_value());
  EXPECT_FALSE(symbolic::unarchive_derivation(forged(spec, [&](GiNaC::matrix& shared, auto& fields) {
    const unsigned k = defined(shared);
    shared = with_definitions(shared, {GiNaC::sin(GiNaC::wild(k + 1)), GiNaC::cos(x)});
    fields["power_time"] = GiNaC::wild(k);
  }), spec).has_value());
  // A wildcard with no definition.
  EXPECT_FALSE(symbolic::unarchive_derivation(forged(spec, [&](auto&, auto& fields) {
    fields["power_time"] = GiNaC::wild(1000000);
  }), spec).has_value());
  // A definition that is a matrix, in Q.
  EXPECT_FALSE(symbolic::unarchive_derivation(forged(spec, [&](GiNaC::matrix& shared, auto& fields) {
    const unsigned k = defined(shared);
    shared = with_definitions(shared, {GiNaC::matrix(2, 2, GiNaC::lst{x, 1, 2, 3})});
    GiNaC::matrix q = GiNaC::ex_to<GiNaC::matrix>(fields["Q"]);
    q(0, 3) = GiNaC::wild(k);
    fields["Q"] = q;
  }), spec).has_value());
  // A chain of 3000 definitions, each the sine of the last.
  EXPECT_FALSE(symbolic::unarchive_derivation(forged(spec, [&](GiNaC::matrix& shared, auto& fields) {
    const unsigned k = defined(shared);
    std::vector<GiNaC::ex> chain{GiNaC::sin(x)};
    for (unsigned i = 1; i < 3000; ++i) chain.push_back(GiNaC::sin(GiNaC::wild(k + i - 1)));
    shared = with_definitions(shared, chain);
    fields["power_time"] = GiNaC::wild(k + 2999);
  }), spec).has_value());
  // 60 definitions, each the product of the sine and the cosine of the last: 2^60 nodes as a tree.
  EXPECT_FALSE(symbolic::unarchive_derivation(forged(spec, [&](GiNaC::matrix& shared, auto& fields) {
    const unsigned k = defined(shared);
    std::vector<GiNaC::ex> doubling{GiNaC::sin(x)};
    for (unsigned i = 1; i < 60; ++i)
      doubling.push_back(GiNaC::sin(GiNaC::wild(k + i - 1)) * GiNaC::cos(GiNaC::wild(k + i - 1)));
    shared = with_definitions(shared, doubling);
    fields["power_time"] = GiNaC::wild(k + 59);
  }), spec).has_value());
  // 2000 levels of nesting in a field itself, no definitions.
  EXPECT_FALSE(symbolic::unarchive_derivation(forged(spec, [&](auto&, auto& fields) {
    GiNaC::ex nested = x;
    for (int i = 0; i < 1000; ++i) nested = GiNaC::pow(nested + 1, 3);
    fields["power_time"] = nested;
  }), spec).has_value());
}

TEST(DerivationArchive, RefusesAnotherModelsAndDamagedBytes) {
  const symbolic::Spec bicycle = load_model_file(test::example("whipple_bicycle.toml"));
  const symbolic::Spec sled = load_model_file(test::example("sled.toml"));
  const std::string bytes = symbolic::archive_derivation(symbolic::derive(bicycle));
  // The sled's table knows none of the bicycle's coordinates.
  EXPECT_FALSE(symbolic::unarchive_derivation(bytes, sled).has_value());
  EXPECT_FALSE(symbolic::unarchive_derivation(bytes.substr(0, bytes.size() / 2), bicycle).has_value());
  EXPECT_FALSE(symbolic::unarchive_derivation("", bicycle).has_value());
  std::string altered = bytes;
  altered[altered.size() / 2] ^= 0x5a;
  // One byte altered anywhere is refused by the checksum (GiNaC's reader, given it, could read on
  // forever or make another expression).
  EXPECT_FALSE(symbolic::unarchive_derivation(altered, bicycle).has_value());
  altered = bytes;
  altered.back() ^= 0x01;
  EXPECT_FALSE(symbolic::unarchive_derivation(altered, bicycle).has_value());
  EXPECT_TRUE(symbolic::unarchive_derivation(bytes, bicycle).has_value());
}

// A derivation of a model with other sizes is refused even where every symbol it names is known.
TEST(DerivationArchive, RefusesADerivationOfOtherSizes) {
  const std::string two = "name = \"two\"\ncoordinates = [\"x\", \"y\"]\nkinetic_energy = \"x'^2/2 + y'^2/2\"\n";
  const std::string three =
      "name = \"three\"\ncoordinates = [\"x\", \"y\", \"z\"]\nkinetic_energy = \"x'^2/2 + y'^2/2 + z'^2/2\"\n";
  const symbolic::Spec a = load_model_string(two, "two.toml"), b = load_model_string(three, "three.toml");
  const std::string bytes = symbolic::archive_derivation(symbolic::derive(a));
  EXPECT_TRUE(symbolic::unarchive_derivation(bytes, a).has_value());
  EXPECT_FALSE(symbolic::unarchive_derivation(bytes, b).has_value());
}

// A cache directory of the test's own, set for the process while the test runs.
class CacheDirectory {
 public:
  CacheDirectory() : dir_(fs::temp_directory_path() / ("nhdyn-derivation-cache-" + std::to_string(::getpid()))) {
    fs::remove_all(dir_);
    const char* old = std::getenv("XDG_CACHE_HOME");
    old_ = old ? std::optional<std::string>(old) : std::nullopt;
    const char* setting = std::getenv("NHDYN_DERIVATION_CACHE");
    old_setting_ = setting ? std::optional<std::string>(setting) : std::nullopt;
    ::setenv("XDG_CACHE_HOME", dir_.c_str(), 1);
    // Every derivation kept, however fast this machine derives it (the default keeps the costly ones).
    ::setenv("NHDYN_DERIVATION_CACHE", "always", 1);
  }
  ~CacheDirectory() {
    if (old_)
      ::setenv("XDG_CACHE_HOME", old_->c_str(), 1);
    else
      ::unsetenv("XDG_CACHE_HOME");
    if (old_setting_)
      ::setenv("NHDYN_DERIVATION_CACHE", old_setting_->c_str(), 1);
    else
      ::unsetenv("NHDYN_DERIVATION_CACHE");
    fs::remove_all(dir_);
  }
  const fs::path& root() const { return dir_; }
  std::vector<fs::path> files() const {
    std::vector<fs::path> out;
    if (fs::exists(dir_ / "nhdyn" / "derivations"))
      for (const auto& entry : fs::directory_iterator(dir_ / "nhdyn" / "derivations")) out.push_back(entry.path());
    return out;
  }

 private:
  fs::path dir_;
  std::optional<std::string> old_, old_setting_;
};

bool stored(const LoadedModel& loaded) { return loaded.description->derivation_was_stored(); }

TEST(DerivationCache, TheSecondLoadReadsTheDerivationAndComputesTheSame) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;
  const ModelSource source = read_model_source(test::example("rattleback.toml"));
  const LoadedModel first = load_model_described(source, {});
  EXPECT_FALSE(stored(first));
  ASSERT_EQ(cache.files().size(), 1U);
  const LoadedModel second = load_model_described(source, {});
  EXPECT_TRUE(stored(second));
  EXPECT_EQ(start_numbers(first.model), start_numbers(second.model));
  // Another --set value is another key (the derivation's checks use the values).
  const LoadedModel other = load_model_described(source, {{"spin", -4.0}});
  EXPECT_FALSE(stored(other));
  EXPECT_EQ(cache.files().size(), 2U);
  // Another text is another key, even with the same name.
  const ModelSource changed = model_source_from_text(source.text + "\n# a comment\n", source.file_name);
  EXPECT_FALSE(stored(load_model_described(changed, {})));
}

TEST(DerivationCache, ADamagedFileIsDerivedAgainAndReplaced) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;
  const ModelSource source = read_model_source(test::example("ball_in_bowl.toml"));
  const LoadedModel first = load_model_described(source, {});
  ASSERT_EQ(cache.files().size(), 1U);
  const fs::path file = cache.files().front();
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  for (const std::string& damaged : {bytes.substr(0, bytes.size() / 2), std::string("not a cache file\n")}) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << damaged;
    const LoadedModel again = load_model_described(source, {});
    EXPECT_FALSE(stored(again));
    EXPECT_EQ(start_numbers(first.model), start_numbers(again.model));
    EXPECT_TRUE(stored(load_model_described(source, {})));  // replaced by a good one
  }
}

// A cache of many files (a shell loop over --set values) keeps the 150 most recently used of them
// once it holds more than 200, the one just written among them.
TEST(DerivationCache, ManyFilesAreTrimmedToTheMostRecentlyUsed) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;
  const fs::path dir = cache.root() / "nhdyn" / "derivations";
  fs::create_directories(dir);
  const auto old = fs::file_time_type::clock::now() - std::chrono::hours(1);
  for (int i = 0; i < 210; ++i) {
    const fs::path file = dir / ("old" + std::to_string(i) + ".derivation");
    std::ofstream(file) << "old";
    fs::last_write_time(file, old + std::chrono::seconds(i));
  }
  std::ofstream(dir / "notes.txt") << "not a derivation: left alone";
  const LoadedModel loaded = load_model_described(read_model_source(test::example("sled.toml")), {});
  const std::vector<fs::path> files = cache.files();
  EXPECT_EQ(files.size(), 151U);  // 150 derivations and the notes
  EXPECT_TRUE(fs::exists(dir / "notes.txt"));
  EXPECT_FALSE(fs::exists(dir / "old0.derivation"));
  EXPECT_TRUE(fs::exists(dir / "old209.derivation"));
  EXPECT_TRUE(stored(load_model_described(read_model_source(test::example("sled.toml")), {})));
}

// By default a costly derivation is kept from its model's second load: the first leaves a mark
// only (a model loaded once pays no archive), the second writes, the third reads.
TEST(DerivationCache, ByDefaultTheSecondLoadKeepsAndTheThirdReads) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;
  ::unsetenv("NHDYN_DERIVATION_CACHE");
  const ModelSource source = read_model_source(test::example("rattleback.toml"));
  const auto count = [&](const char* extension) {
    int k = 0;
    for (const fs::path& f : cache.files()) k += f.extension() == extension;
    return k;
  };
  EXPECT_FALSE(stored(load_model_described(source, {})));
  EXPECT_EQ(count(".seen"), 1);
  EXPECT_EQ(count(".derivation"), 0);
  EXPECT_FALSE(stored(load_model_described(source, {})));
  EXPECT_EQ(count(".seen"), 0);
  EXPECT_EQ(count(".derivation"), 1);
  EXPECT_TRUE(stored(load_model_described(source, {})));
}

// The mark of a first load is made only where nothing is: a named pipe at its place (whose
// opening for writing waits for a reader) and a dangling link (whose target the mark would create)
// are left as they are, and the model loads.
TEST(DerivationCache, APipeOrALinkAtTheMarksPlaceIsLeftAlone) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;
  ::unsetenv("NHDYN_DERIVATION_CACHE");
  const ModelSource source = read_model_source(test::example("rattleback.toml"));
  const LoadedModel first = load_model_described(source, {});
  ASSERT_EQ(cache.files().size(), 1U);
  const fs::path mark = cache.files().front();
  ASSERT_EQ(mark.extension(), ".seen");
  fs::remove(mark);
  ASSERT_EQ(::mkfifo(mark.c_str(), 0600), 0);
  const LoadedModel piped = load_model_described(source, {});
  EXPECT_FALSE(stored(piped));
  EXPECT_EQ(start_numbers(first.model), start_numbers(piped.model));
  EXPECT_TRUE(fs::is_fifo(mark));
  fs::remove(mark);
  const fs::path target = cache.root() / "elsewhere";
  fs::create_symlink(target, mark);
  const LoadedModel linked = load_model_described(source, {});
  EXPECT_EQ(start_numbers(first.model), start_numbers(linked.model));
  EXPECT_FALSE(fs::exists(target));
}

TEST(DerivationCache, OffMeansNoFile) {
  const CacheDirectory cache;
  for (const char* off : {"off", "OFF", "0", "false", "No"}) {
    ::setenv("NHDYN_DERIVATION_CACHE", off, 1);
    const LoadedModel loaded = load_model_described(read_model_source(test::example("sled.toml")), {});
    EXPECT_FALSE(stored(loaded)) << off;
    EXPECT_TRUE(cache.files().empty()) << off;
  }
}

// A relative XDG_CACHE_HOME is ignored, as the XDG Base Directory rules say: the cache goes under
// $HOME/.cache, never into a folder of the current directory.
TEST(DerivationCache, ARelativeXdgCacheHomeIsIgnored) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;  // restores XDG_CACHE_HOME and NHDYN_DERIVATION_CACHE after
  const char* home = std::getenv("HOME");
  const std::optional<std::string> old_home = home ? std::optional<std::string>(home) : std::nullopt;
  const fs::path fake_home = cache.root() / "home";
  ::setenv("HOME", fake_home.c_str(), 1);
  ::setenv("XDG_CACHE_HOME", "relative-cache", 1);
  const fs::path here = fs::current_path();
  fs::create_directories(cache.root() / "work");
  fs::current_path(cache.root() / "work");
  load_model_described(read_model_source(test::example("sled.toml")), {});
  fs::current_path(here);
  if (old_home)
    ::setenv("HOME", old_home->c_str(), 1);
  else
    ::unsetenv("HOME");
  EXPECT_FALSE(fs::exists(cache.root() / "work" / "relative-cache"));
  EXPECT_TRUE(fs::exists(fake_home / ".cache" / "nhdyn" / "derivations"));
}

// What sits at the file's place and is not a file is passed by, never opened: a named pipe (whose
// opening waits for a writer) or a link to /dev/zero (a line without end); the model derives.
TEST(DerivationCache, APipeOrADeviceAtTheFilesPlaceIsPassedBy) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;
  const ModelSource source = read_model_source(test::example("ball_in_bowl.toml"));
  const LoadedModel first = load_model_described(source, {});
  ASSERT_EQ(cache.files().size(), 1U);
  const fs::path file = cache.files().front();
  fs::remove(file);
  ASSERT_EQ(::mkfifo(file.c_str(), 0600), 0);
  const LoadedModel piped = load_model_described(source, {});
  EXPECT_FALSE(stored(piped));
  EXPECT_EQ(start_numbers(first.model), start_numbers(piped.model));
  fs::remove(file);
  fs::create_symlink("/dev/zero", file);
  const LoadedModel zero = load_model_described(source, {});
  EXPECT_FALSE(stored(zero));
  EXPECT_EQ(start_numbers(first.model), start_numbers(zero.model));
}

// The temporary file of a writer that died before its rename (SIGKILL) goes once an hour old;
// a younger one (a writer at work) stays.
TEST(DerivationCache, TemporariesOfDeadWritersGo) {
  if (detail::build_identity().empty()) GTEST_SKIP() << "this build has no GNU build-id: no derivation cache";
  const CacheDirectory cache;
  const fs::path dir = cache.root() / "nhdyn" / "derivations";
  fs::create_directories(dir);
  const fs::path dead = dir / ".0123.derivation.999-0.tmp", live = dir / ".4567.derivation.998-0.tmp";
  std::ofstream(dead) << "half";
  std::ofstream(live) << "half";
  fs::last_write_time(dead, fs::file_time_type::clock::now() - std::chrono::hours(2));
  load_model_described(read_model_source(test::example("ball_in_bowl.toml")), {});
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(live));
}

}  // namespace
}  // namespace nhdyn
