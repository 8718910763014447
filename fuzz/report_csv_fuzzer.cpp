// libFuzzer target for the CSV reader of `nhdyn report RESULT.csv --model sled`: any bytes are
// written to a file and read as apps/nhdyn/report.cpp reads a result — load_csv (comment lines,
// byte-order mark, numbers), the provenance header (parse_provenance, check_provenance against
// the built-in sled), the columns the model expects, the times (finite, never decreasing) — and a
// table that passes is made into the page (write_model_report). Every rejection must be an
// nhdyn::Error (the CLI's exit 2); any other exception aborts, as do a crash, a leak and undefined
// behaviour. Seed corpus: fuzz/csv_corpus/ (nhdyn's own CSV of the sled and variants of it).
// Built and run by fuzz/run (see fuzz/CMakeLists.txt).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/load_model.hpp"
#include "nhdyn/frontend/provenance.hpp"
#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/provenance.hpp"
#include "nhdyn/io/report.hpp"
#include "nhdyn/io/results.hpp"

namespace {

namespace fs = std::filesystem;

// The input and the page, in a folder of this process's own, removed at exit.
struct Files {
  fs::path dir = fs::temp_directory_path() / ("nhdyn-csv-fuzz-" + std::to_string(::getpid()));
  fs::path csv = dir / "result.csv";
  fs::path html = dir / "report.html";
  Files() { fs::create_directories(dir); }
  ~Files() {
    std::error_code ignored;
    fs::remove_all(dir, ignored);
  }
};

void read_as_report(const Files& files) {
  const nhdyn::CsvTable table = nhdyn::load_csv(files.csv);
  const nhdyn::ModelSource source = nhdyn::read_model_source("sled");
  nhdyn::ParameterOverrides overrides;
  if (const std::optional<nhdyn::Provenance> provenance = nhdyn::parse_provenance(table.comments, files.csv.string()))
    overrides = nhdyn::check_provenance(*provenance, source, files.csv.string());
  const nhdyn::LoadedModel resolved = nhdyn::load_model_described(source, overrides);
  nhdyn::check_report_columns(table.header, nhdyn::make_result_columns(resolved.model), files.csv.string(),
                              resolved.model.name);
  nhdyn::check_report_times(table, files.csv.string());
  nhdyn::ReportOptions options;
  options.max_frames = 50;  // the page's size stays small whatever the rows
  (void)nhdyn::write_model_report(resolved.model, resolved.description.get(), table, "fuzz", {{"results", "fuzz"}},
                                  files.html, options);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Files files;
  {
    std::ofstream out(files.csv, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) {
      std::fprintf(stderr, "cannot write %s\n", files.csv.c_str());
      std::abort();
    }
  }
  try {
    read_as_report(files);
  } catch (const nhdyn::Error& e) {
    if (std::getenv("NHDYN_FUZZ_VERBOSE")) std::fprintf(stderr, "refused: %s\n", e.what());
    // A clear rejection: what the reader is for.
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error (the CLI would exit 3): %s\n", e.what());
    std::abort();
  }
  return 0;
}
