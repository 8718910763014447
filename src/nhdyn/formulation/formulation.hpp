// The four formulations of the equations of motion behind one entry point, chosen at run time:
// sanh (the stacked Do Sanh system, the default), lagrange (KKT), udwadia-kalaba and nullspace
// (Maggi). Each fills q'' and the reactions R in Data (and the multipliers where they exist).
// docs/notation.md sections 3 and 5.
#pragma once

#include <array>
#include <string_view>

#include "nhdyn/core/names.hpp"
#include "nhdyn/core/status.hpp"
#include "nhdyn/formulation/baumgarte.hpp"
#include "nhdyn/formulation/program_feedback.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/model.hpp"

namespace nhdyn {

// enum class Formulation { sanh, lagrange, udwadia_kalaba, nullspace } is declared in model/data.hpp,
// because make_data sizes the workspace of one formulation and model/ is below formulation/.

// Where D comes from (docs/notation.md section 3): the model's analytic D, coordinate
// partitioning, or an orthonormal basis of null(b) from a QR factorization (the default).
enum class Complement { qr, partition, analytic };

struct FormulationOptions {
  // A constructor rather than an aggregate, so that the usual {method, complement} leaves the
  // gains at their defaults without -Wmissing-field-initializers.
  FormulationOptions(Formulation m = Formulation::sanh, Complement c = Complement::qr, BaumgarteGains gains = {})
      : method(m), complement(c), baumgarte(gains) {}
  Formulation method = Formulation::sanh;
  Complement complement = Complement::qr;
  BaumgarteGains baumgarte;  // off unless enabled (baumgarte.hpp)
  ProgramFeedback program_feedback;  // off unless enabled; only for a model with programs (program_motion.hpp)
};

// The formulations and the choices of D, once (core/names.hpp): their names in the CLI, model
// files and Python, and what each formulation can do. A new formulation adds its enumerator
// of Formulation (model/data.hpp), its line here and its case in compute_acceleration.
struct FormulationInfo {
  Formulation value;
  std::string_view name;
  bool sparse;  // has sparse kernels (sparse_sanh.hpp, sparse_lagrange.hpp)
};
inline constexpr std::array<FormulationInfo, 4> kFormulations{{
    {Formulation::sanh, "sanh", true},
    {Formulation::lagrange, "lagrange", true},
    {Formulation::udwadia_kalaba, "udwadia-kalaba", false},
    {Formulation::nullspace, "nullspace", false},
}};

using ComplementInfo = Named<Complement>;
inline constexpr std::array<ComplementInfo, 3> kComplements{
    {{Complement::qr, "qr"}, {Complement::partition, "partition"}, {Complement::analytic, "analytic"}}};

// Its name in kFormulations: "sanh", "lagrange", "udwadia-kalaba", "nullspace".
std::string_view formulation_name(Formulation method);
Formulation parse_formulation(std::string_view name);  // throws InputError listing valid names
// Its name in kComplements: "qr", "partition", "analytic".
std::string_view complement_name(Complement complement);
Complement parse_complement(std::string_view name);  // throws InputError listing valid names

// Requires compute_terms for the current state (Stage::terms). For a model with programs
// (model.m() > 0) sanh solves program motion (program_motion.hpp), which writes data.motion too;
// the other formulations refuse such a model with InputError. Writes data.qdd, data.R,
// data.lambda (when the method has multipliers), data.D (sanh, nullspace) and sets
// Stage::acceleration. On the sparse path (data.sparse) it runs the sparse kernels of sanh
// (sparse_sanh.hpp, always with the partitioned D whatever `options.complement` says) or
// lagrange (sparse_lagrange.hpp). Throws std::logic_error when data was made for another
// formulation (DataOptions::method) or, on the sparse path, for udwadia-kalaba and nullspace,
// which have no sparse kernels (make_data with that method takes the dense path instead). With Baumgarte gains enabled, the formulation solves the stabilized
// constraint (b0 + data.stabilization in place of b0); data.b0 keeps the model's b0 on return.
// Allocates nothing. On numerical trouble returns a non-ok status, records
// it in data, and leaves stage at Stage::terms; explain_failure (diagnosis.hpp) gives the words.
Status compute_acceleration(const Model& model, Data& data, const FormulationOptions& options);

// Terms then acceleration at (t, q, v): the right-hand side of the equations of motion.
Status compute_dynamics(const Model& model, Data& data, const FormulationOptions& options, double t,
                        const double* q, const double* v);

}  // namespace nhdyn
