#include "nhdyn/studies/spread_masses.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

#include "nhdyn/analysis/initial_state.hpp"
#include "nhdyn/core/error.hpp"
#include "nhdyn/formulation/formulation.hpp"
#include "nhdyn/model/data.hpp"
#include "nhdyn/model/terms.hpp"
#include "nhdyn/symbolic/compile.hpp"
#include "nhdyn/symbolic/derivation.hpp"
#include "nhdyn/symbolic/precise_reference.hpp"

namespace nhdyn {
namespace {

bool has_parameter(const symbolic::Spec& spec, const std::string& name) {
  return std::any_of(spec.parameters.begin(), spec.parameters.end(),
                     [&](const symbolic::SpecParameter& p) { return p.name == name; });
}

void check_parameter(const symbolic::Spec& spec, const std::string& name) {
  if (!has_parameter(spec, name)) {
    std::string names;
    for (const symbolic::SpecParameter& p : spec.parameters) names += (names.empty() ? "" : ", ") + p.name;
    throw InputError(fmt::format("model '{}' has no parameter '{}' to spread its masses with (its parameters: {}); "
                                 "write the masses in terms of '{}', as examples/spread_masses.toml does",
                                 spec.name, name, names.empty() ? "none" : names, name));
  }
}

double condition_number(const Matrix& A) {
  const Eigen::JacobiSVD<Matrix> svd(A);
  const Vector& sigma = svd.singularValues();
  return sigma(sigma.size() - 1) > 0.0 ? sigma(0) / sigma(sigma.size() - 1) : std::numeric_limits<double>::infinity();
}

double norm(const std::vector<GiNaC::numeric>& x) {
  double sum = 0.0;
  for (const GiNaC::numeric& xi : x) sum += xi.to_double() * xi.to_double();
  return std::sqrt(sum);
}

}  // namespace

std::vector<SpreadMassesState> make_spread_masses_states(const symbolic::Spec& spec, const std::string& parameter,
                                                         int samples) {
  check_parameter(spec, parameter);
  symbolic::Spec unit = spec;
  unit.set_parameter(parameter, 1.0);
  const Model model = symbolic::compile_model(unit);
  Data data = make_data(model);
  std::vector<SpreadMassesState> states;
  states.push_back({model.t0, model.q0, model.v0});
  for (int j = 1; j < samples; ++j) {
    // A fixed, irregular pattern (no random generator, so every platform gets the same states).
    Vector q = model.q0, v = model.v0;
    for (int i = 0; i < model.n(); ++i) {
      q(i) += 0.4 * std::sin(1.7 * j + 2.3 * i + 0.5);
      v(i) += 1.0 * std::cos(2.9 * j + 1.1 * i + 0.2);
    }
    const InitialFix fixed = fix_initial_state(model, data, model.t0, q, v);
    states.push_back({model.t0, fixed.q, fixed.v});
  }
  return states;
}

void check_spread_masses_options(const SpreadMassesOptions& options) {
  if (options.ratios.empty()) throw InputError("the spread-masses study needs at least one mass ratio (--ratios)");
  for (double ratio : options.ratios)
    if (!(ratio > 0.0 && std::isfinite(ratio)))
      throw InputError(
          fmt::format("--ratios: mass ratio {} is not a positive number; give ratios such as 1,1e6,1e12", ratio));
  if (options.samples < 1)
    throw InputError(fmt::format("--samples {0}: {0} samples are too few; the study needs at least 1 state per ratio",
                                 options.samples));
  // Each state costs a reference in many digits (about 1.5 ms at 50): 1e8 grew the memory by 70 MB
  // a second for days of work before the first result.
  if (options.samples > kMaxSpreadMassesSamples)
    throw InputError(fmt::format("--samples {}: at most {} states per ratio (each needs a reference in {} digits, about "
                                 "1.5 ms at 50 digits); give fewer",
                                 options.samples, kMaxSpreadMassesSamples, options.digits));
  if (options.digits < 20)
    throw InputError(fmt::format("--digits {0}: {0} digits is too few for a reference to double precision; ask for 20 "
                                 "or more (50 is the default)",
                                 options.digits));
  if (options.digits > kMaxSpreadMassesDigits)
    throw InputError(fmt::format("--digits {}: at most {} digits (50 is the default: double precision needs 20)",
                                 options.digits, kMaxSpreadMassesDigits));
}

SpreadMasses study_spread_masses(const symbolic::Spec& spec, const SpreadMassesOptions& options) {
  check_spread_masses_options(options);
  check_parameter(spec, options.parameter);

  const symbolic::Derivation derivation = symbolic::derive(spec);
  SpreadMasses out;
  out.model = spec.name;
  out.digits = options.digits;
  out.formulations = options.formulations;
  const bool analytic = derivation.D.has_value();
  if (out.formulations.empty()) {
    out.formulations = {{Formulation::sanh, Complement::qr}, {Formulation::sanh, Complement::partition}};
    if (analytic) out.formulations.push_back({Formulation::sanh, Complement::analytic});
    for (Formulation m : {Formulation::lagrange, Formulation::udwadia_kalaba, Formulation::nullspace}) out.formulations.push_back({m, Complement::qr});
  }
  for (const StudyFormulation& f : out.formulations)
    if (f.complement == Complement::analytic && f.method == Formulation::sanh && !analytic)
      throw InputError(fmt::format("model '{}' gives no analytic complement D, so {} cannot run; leave it out",
                                   spec.name, formulation_label(f)));
  out.states = make_spread_masses_states(spec, options.parameter, options.samples);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (double ratio : options.ratios) {
    symbolic::Spec scaled = spec;
    scaled.set_parameter(options.parameter, ratio);
    const Model model = symbolic::compile_model(scaled, derivation);
    Data data = make_data(model);
    SpreadMassesRatio row;
    row.ratio = ratio;
    std::vector<SpreadMassesPoint> points(out.formulations.size());
    for (const SpreadMassesState& state : out.states) {
      const symbolic::PreciseAcceleration ref = symbolic::calc_precise_acceleration(
          scaled, derivation, state.t, {state.q.data(), static_cast<std::size_t>(state.q.size())},
          {state.v.data(), static_cast<std::size_t>(state.v.size())}, options.digits);
      row.reference_error = std::max(row.reference_error, ref.estimated_error);
      row.norm_qdd = std::max(row.norm_qdd, norm(ref.qdd));
      row.norm_R = std::max(row.norm_R, norm(ref.R));
      // The terms are the same for every formulation: evaluate them, and the exact solution of
      // the problem as they pose it, once per state.
      if (compute_terms(model, data, state.t, state.q.data(), state.v.data()) != Status::ok)
        throw ModelError(fmt::format("model '{}' at {} = {:g}: the terms are not finite at a sample state", spec.name,
                                     options.parameter, ratio));
      row.cond_A = std::max(row.cond_A, condition_number(data.A));
      const Vector h = data.Q + data.G;
      const symbolic::PreciseAcceleration solve_ref =
          symbolic::calc_precise_solution(data.A, h, data.b, data.b0, options.digits);
      for (std::size_t f = 0; f < out.formulations.size(); ++f) {
        SpreadMassesPoint& point = points[f];
        if (compute_terms(model, data, state.t, state.q.data(), state.v.data()) != Status::ok)
          throw ModelError(fmt::format("model '{}' at {} = {:g}: the terms are not finite at a sample state",
                                       spec.name, options.parameter, ratio));
        const StudyFormulation& formulation = out.formulations[f];
        const Status status =
            compute_acceleration(model, data, FormulationOptions(formulation.method, formulation.complement));
        if (status != Status::ok) {
          if (point.failures++ == 0) point.failure = status;
          point.error_qdd = point.error_R = point.solve_error_qdd = point.solve_error_R = point.residual = nan;
          continue;
        }
        const std::span<const double> qdd(data.qdd.data(), static_cast<std::size_t>(data.qdd.size()));
        const std::span<const double> R(data.R.data(), static_cast<std::size_t>(data.R.size()));
        const double residual = data.b0.size() > 0 ? (data.b * data.qdd + data.b0).cwiseAbs().maxCoeff() : 0.0;
        // std::max would drop a NaN recorded by an earlier failure; keep it.
        if (point.failures == 0) {
          const auto worst = [](double& to, double value) { to = std::max(to, value); };
          worst(point.error_qdd, symbolic::calc_relative_error(qdd, ref.qdd, options.digits));
          worst(point.error_R, symbolic::calc_relative_error(R, ref.R, options.digits));
          worst(point.solve_error_qdd, symbolic::calc_relative_error(qdd, solve_ref.qdd, options.digits));
          worst(point.solve_error_R, symbolic::calc_relative_error(R, solve_ref.R, options.digits));
          worst(point.residual, residual);
        }
      }
    }
    out.ratios.push_back(row);
    out.points.insert(out.points.end(), points.begin(), points.end());
  }
  return out;
}

}  // namespace nhdyn
