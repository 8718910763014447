// libFuzzer target for the model-file loader: any bytes go through load_model_string, and a file
// that loads is compiled (derive + compile_model) and its terms evaluated once at the initial
// state. Every rejection must be an nhdyn::Error (the CLI's exit 2); any other exception is what
// the CLI reports as "internal error" with exit 3, and aborts here, as do a crash, a leak and
// undefined behaviour. An input that takes more than 10 s is a bug too (fuzz/run: -timeout=10).
// Built and run by fuzz/run (see fuzz/CMakeLists.txt).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string_view>
#include <vector>

#include "nhdyn/core/error.hpp"
#include "nhdyn/frontend/model_file.hpp"
#include "nhdyn/model/model.hpp"
#include "nhdyn/symbolic/compile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const nhdyn::symbolic::Spec spec = nhdyn::load_model_string(text, "fuzz.toml");
    const nhdyn::Model model = nhdyn::symbolic::compile_model(spec);
    const auto n = static_cast<std::size_t>(model.n()), s = static_cast<std::size_t>(model.s());
    std::vector<double> scratch(model.evaluator->scratch_size()), A(n * n), Q(n), G(n), b(s * n), b0(s);
    model.evaluator->terms(model.t0, model.q0.data(), model.v0.data(), scratch.data(),
                           {A.data(), Q.data(), G.data(), b.data(), b0.data()});
  } catch (const nhdyn::Error&) {
    // A clear rejection: what the loader is for.
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error (the CLI would exit 3): %s\n", e.what());
    std::abort();
  }
  return 0;
}
