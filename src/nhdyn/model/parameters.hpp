// Parameters as data: the values a Model computes with, changed at run time without recompiling.
// A parameter is either a base one (a number) or a derived one (an expression in numbers, the
// constants pi and e, and other parameters, such as k = "4*m"), re-evaluated whenever a parameter
// it uses changes. Setting a parameter re-binds the Model's Evaluator to the new values
// (Evaluator::with_parameters: the compiled tapes fold their parameter-only parts once, here,
// not at every call) and re-evaluates the initial state where it depends on the parameters.
// No GiNaC: the expressions of parameter values have their own small evaluator, so that the
// command line (`--set NAME=EXPR`) and the Python package use this without the symbolic layer.
// docs/design.md, "Parameters as data"; docs/model-format.md, [parameters].
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "nhdyn/model/model.hpp"

namespace nhdyn {

// The value of a parameter expression: numbers (1, 2.5, 1e-3), + - * / and ^ (or **, right
// associative, binding tighter than a unary minus: -2^2 = -4), parentheses, the functions sin,
// cos, tan, asin, acos, atan, atan2(y, x), sinh, cosh, tanh, exp, log, sqrt, abs, the constants
// pi and e, and the names in `known` (a parameter named e or pi hides the constant). Throws
// InputError naming the unknown name (and the nearest known one) or the column of a syntax error.
// The result is not checked (see check_parameter_value).
double calc_parameter_expression(std::string_view text, const std::vector<Parameter>& known);

// The parameter names an expression uses, in order of first use (constants and functions left
// out). Throws InputError on a syntax error.
std::vector<std::string> calc_expression_names(std::string_view text, const std::vector<Parameter>& known);

// Throws InputError unless `value` can serve as the value of parameter `name`: finite, not
// subnormal (0 < |x| < 2.2e-308 has lost precision), and at most sqrt(DBL_MAX) = 1.3e154 in
// magnitude (the square of a larger one, the first product a term forms, overflows).
void check_parameter_value(std::string_view name, double value);

// Re-evaluates the derived parameters of `parameters` from the base ones, each after the ones it
// uses. Throws InputError naming the parameters of a cyclic definition, an unknown name in a
// definition (with the nearest known one) or a value check_parameter_value refuses; `model` names
// the model in messages.
void update_parameters(std::vector<Parameter>& parameters, std::string_view model);

// --set NAME=EXPR on a list of parameters: an expression without parameter names makes NAME a
// base parameter with its value, one that uses parameters makes NAME a derived parameter that
// follows them. Every derived parameter is then re-evaluated. Throws InputError for an unknown
// NAME (with the nearest known one), an expression that does not evaluate, or a cycle.
void set_parameter_expression(std::vector<Parameter>& parameters, std::string_view name, std::string_view expression,
                              std::string_view model);
// "NAME=EXPR" split at its first '=' into NAME and EXPR, both as written (NAME + "=" + EXPR is
// `set` again); throws InputError saying how to write it when there is no '=' or no NAME.
std::pair<std::string, std::string> split_parameter_set(std::string_view set);
// Each "NAME=EXPR" of `sets` in turn, as set_parameter_expression.
void apply_parameter_sets(std::vector<Parameter>& parameters, const std::vector<std::string>& sets,
                          std::string_view model);

// The parameter called `name`; throws InputError naming the model's parameters and the nearest.
const Parameter& find_parameter(const Model& model, std::string_view name);
// Its current value.
double get_parameter(const Model& model, std::string_view name);

// Sets a parameter of `model` (it becomes a base parameter if it was derived), re-evaluates the
// derived ones, re-binds the evaluator and re-evaluates the initial state where the model's
// depends on the parameters (so set q0 and v0 after the parameters). Throws InputError for an
// unknown name (naming the nearest known one), a value check_parameter_value refuses, or values
// the model refuses (a sled with rho <= a); the model is then left unchanged. Cost: that of
// preparing the compiled tapes once (no symbolic work).
void set_parameter(Model& model, std::string_view name, double value);
// The same with an expression of numbers, constants and other parameters (`--set lambda=pi/10`).
void set_parameter_expression(Model& model, std::string_view name, std::string_view expression);
// Each "NAME=EXPR" of `sets` in turn (the command line's --set), then one re-binding.
void apply_parameter_sets(Model& model, const std::vector<std::string>& sets);

// Throws InputError, naming the file's line, the entry and its text, where one of
// model.positive_values is not positive at `parameters` (a --set r=-0.1 of a ball's radius), or
// where the sizes of one contact shape are more than kLargestSizeRatio apart (an ellipsoid 1e-100
// thin: to double precision flat, its contact point undefined across its rim).
constexpr double kLargestSizeRatio = 1e6;
void check_positive_values(const Model& model, const std::vector<Parameter>& parameters);

// Re-binds `model`'s evaluator to the values of model.parameters (after re-evaluating the derived
// ones) and re-evaluates its initial state; what set_parameter does after changing a value.
void rebind_parameters(Model& model);

}  // namespace nhdyn
