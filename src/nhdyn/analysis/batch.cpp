#include "nhdyn/analysis/batch.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <system_error>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "nhdyn/analysis/residuals.hpp"
#include "nhdyn/core/error.hpp"

namespace nhdyn {

void Trajectory::reset(const Model& model, long expected_rows) {
  n = model.n();
  residual_columns = model.position_constraints() + model.velocity_constraints() + model.s();
  has_energy = model.evaluator && model.evaluator->has_energy();
  balance_columns = model.evaluator && model.evaluator->has_energy_balance() ? kEnergyBalanceColumns : 0;
  actuator_columns = model.m();
  program_residual_columns = 0;
  for (const ProgramConstraint& p : model.program_constraints)
    program_residual_columns += p.level == ConstraintLevel::position ? 3 : p.level == ConstraintLevel::velocity ? 2 : 1;
  contact_columns = static_cast<int>(contact_force_columns(model).size());
  output_columns = model.outputs.count();
  for (std::vector<double>* column :
       {&t, &q, &v, &qdd, &R, &residuals, &energy, &balance, &u, &program_residuals, &contact_forces, &outputs})
    column->clear();
  const auto rows = static_cast<std::size_t>(std::max(0L, expected_rows));
  const auto un = static_cast<std::size_t>(n);
  t.reserve(rows);
  q.reserve(rows * un);
  v.reserve(rows * un);
  qdd.reserve(rows * un);
  R.reserve(rows * un);
  residuals.reserve(rows * static_cast<std::size_t>(residual_columns));
  if (has_energy) energy.reserve(rows);
  balance.reserve(rows * static_cast<std::size_t>(balance_columns));
  u.reserve(rows * static_cast<std::size_t>(actuator_columns));
  program_residuals.reserve(rows * static_cast<std::size_t>(program_residual_columns));
  contact_forces.reserve(rows * static_cast<std::size_t>(contact_columns));
  outputs.reserve(rows * static_cast<std::size_t>(output_columns));
}

void Trajectory::append(const Data& data) {
  t.push_back(data.t);
  q.insert(q.end(), data.q.data(), data.q.data() + n);
  v.insert(v.end(), data.v.data(), data.v.data() + n);
  qdd.insert(qdd.end(), data.qdd.data(), data.qdd.data() + n);
  R.insert(R.end(), data.R.data(), data.R.data() + n);
  residuals.insert(residuals.end(), data.phi.data(), data.phi.data() + data.phi.size());
  residuals.insert(residuals.end(), data.f.data(), data.f.data() + data.f.size());
  residuals.insert(residuals.end(), data.e.data(), data.e.data() + data.e.size());
  if (has_energy) energy.push_back(data.energy);
  if (balance_columns > 0) {
    double row[kEnergyBalanceColumns];
    fill_energy_balance(data, row);
    balance.insert(balance.end(), row, row + kEnergyBalanceColumns);
  }
  if (actuator_columns > 0) {
    const ProgramMotionData& w = data.motion;
    u.insert(u.end(), w.u.data(), w.u.data() + w.u.size());
    for (const Vector* level : {&w.phi, &w.f, &w.e})
      program_residuals.insert(program_residuals.end(), level->data(), level->data() + level->size());
  }
  if (contact_columns > 0) {
    const ContactForceData& c = data.contact;
    contact_forces.insert(contact_forces.end(), c.values.data(), c.values.data() + c.values.size());
    contact_forces.push_back(c.residual);
    append_contact_mode_values(data, contact_forces);  // model/contact_modes.hpp: after the forces
  }
  outputs.insert(outputs.end(), data.outputs.values.data(), data.outputs.values.data() + output_columns);
}

int max_batch_threads() {
  const int cores = static_cast<int>(std::thread::hardware_concurrency());
  return std::max(8, 4 * std::max(cores, 1));
}

void check_batch_threads(int threads) {
  if (threads < 0)
    throw InputError(
        fmt::format("the number of threads (--threads) = {} must be 0 (every core) or a positive number", threads));
}

int batch_threads(int threads, std::size_t runs) {
  int count = threads > 0 ? std::min(threads, max_batch_threads()) : static_cast<int>(std::thread::hardware_concurrency());
  count = std::max(count, 1);
  return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(count), std::max<std::size_t>(runs, 1)));
}

namespace {

void run_one(const BatchRun& run, const BatchOptions& options, BatchResult& result) {
  try {
    const Model* model = run.model.get();
    Model changed;
    if (run.q0 || run.v0) {  // the run's own copy: Model is cheap to copy (the evaluator is shared)
      changed = *run.model;
      if (run.q0) changed.q0 = *run.q0;
      if (run.v0) changed.v0 = *run.v0;
      model = &changed;
    }
    long expected = 0;
    if (options.keep_trajectories && options.simulation.output_step > 0.0 && options.simulation.t_end > model->t0)
      expected = static_cast<long>(std::min(1e7, (options.simulation.t_end - model->t0) / options.simulation.output_step)) + 2;
    result.trajectory.reset(*model, expected);
    const int n = model->n();
    result.q_end.resize(n);
    result.v_end.resize(n);
    bool any_row = false;
    result.summary = simulate(*model, options.simulation, [&](const Data& data) {
      if (options.keep_trajectories) result.trajectory.append(data);
      result.q_end = data.q;
      result.v_end = data.v;
      any_row = true;
    });
    if (!any_row) {
      result.q_end.resize(0);
      result.v_end.resize(0);
    }
    result.ok = result.summary.status == Status::ok;
    if (!result.ok)
      result.message = fmt::format("failed at t = {:.6g}: {}", result.summary.t_reached, result.summary.message);
  } catch (const std::exception& e) {  // bad initial state, options refused for this model, ...
    result.ok = false;
    result.message = e.what();
    result.q_end.resize(0);
    result.v_end.resize(0);
  }
}

}  // namespace

std::vector<BatchResult> simulate_batch(const std::vector<BatchRun>& runs, const BatchOptions& options) {
  check_batch_threads(options.threads);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const BatchRun& run = runs[i];
    if (!run.model) throw InputError(fmt::format("batch run {} has no model", i));
    const int n = run.model->n();
    if (run.q0 && run.q0->size() != n)
      throw InputError(fmt::format("batch run {}: {} initial coordinates for a model with {} ({})", i, run.q0->size(),
                                   n, run.model->name));
    if (run.v0 && run.v0->size() != n)
      throw InputError(fmt::format("batch run {}: {} initial velocities for a model with {} ({})", i, run.v0->size(),
                                   n, run.model->name));
    // Refused with the others, before any run: as a failed run it read as the model's overflow.
    for (int k = 0; k < n; ++k) {
      const std::string& name = run.model->coordinates[static_cast<std::size_t>(k)];
      if (run.q0 && !std::isfinite((*run.q0)(k)))
        throw InputError(fmt::format("batch run {}: the initial value {}(0) = {} is not a finite number", i, name,
                                     (*run.q0)(k)));
      if (run.v0 && !std::isfinite((*run.v0)(k)))
        throw InputError(fmt::format("batch run {}: the initial value {}'(0) = {} is not a finite number", i, name,
                                     (*run.v0)(k)));
    }
  }
  std::vector<BatchResult> results(runs.size());
  for (BatchResult& result : results) result.interrupted = true;  // until its run starts
  const int threads = batch_threads(options.threads, runs.size());
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::atomic<int> working{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto work = [&] {
    for (std::size_t i = next.fetch_add(1); i < runs.size() && !stop.load(); i = next.fetch_add(1)) {
      results[i].interrupted = false;
      run_one(runs[i], options, results[i]);
      if (!options.on_result) continue;
      try {
        options.on_result(i, results[i]);
      } catch (...) {
        const std::lock_guard lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        stop = true;
      }
    }
    working.fetch_sub(1);
  };
  // The calling thread is one of the workers unless it must poll keep_going; a thread the system
  // refuses to create (limits on processes or memory) leaves fewer workers, never an abandoned
  // joinable thread (std::terminate).
  const bool poll = static_cast<bool>(options.keep_going);
  std::vector<std::thread> pool;
  const int spawn = poll ? threads : threads - 1;
  pool.reserve(static_cast<std::size_t>(std::max(spawn, 0)));
  for (int i = 0; i < spawn; ++i) {
    working.fetch_add(1);
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      working.fetch_sub(1);
      break;
    }
  }
  if (!poll || pool.empty()) {
    working.fetch_add(1);
    work();
  } else {
    while (working.load() > 0) {
      if (!stop.load() && !options.keep_going()) stop = true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  for (std::thread& thread : pool) thread.join();
  for (BatchResult& result : results)
    if (result.interrupted) result.message = "not run: the batch was interrupted";
  if (failure) std::rethrow_exception(failure);
  return results;
}

std::vector<std::string> format_batch_unmet_stops(const std::vector<std::vector<std::string>>& unmet_stops) {
  // Each sentence once, in the order of the first run that has it, with the runs it holds for.
  std::vector<std::pair<std::string, std::vector<std::size_t>>> groups;
  for (std::size_t run = 0; run < unmet_stops.size(); ++run)
    for (const std::string& sentence : unmet_stops[run]) {
      auto group = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == sentence; });
      if (group == groups.end()) group = groups.insert(groups.end(), {sentence, {}});
      group->second.push_back(run);
    }
  constexpr std::size_t kListed = 20;
  std::vector<std::string> out;
  for (const auto& [sentence, runs] : groups) {
    if (runs.size() == unmet_stops.size()) {
      out.push_back(fmt::format("{} (every run of {})", sentence, runs.size()));
      continue;
    }
    std::string list;
    const std::size_t listed = std::min(runs.size(), kListed);
    for (std::size_t i = 0; i < listed; ++i)
      list += fmt::format("{}{}", i == 0 ? "" : (i + 1 == runs.size() ? " and " : ", "), runs[i]);
    if (runs.size() > listed) list += fmt::format(" and {} more", runs.size() - listed);
    out.push_back(fmt::format("{} ({} {} of {})", sentence, runs.size() == 1 ? "run" : "runs", list,
                              unmet_stops.size()));
  }
  return out;
}

}  // namespace nhdyn
