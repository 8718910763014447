// What the commands read from a model file's description (symbolic/description.hpp) without
// seeing GiNaC: its name and size, its equations as text or LaTeX, its generated C++, the angles of
// its scene, and the Spec itself by reference for the studies that build on it. Each reads what
// load_model_described (frontend/load_model.hpp) kept: nothing here derives a model a second time.
#pragma once

#include <string>
#include <vector>

#include "nhdyn/frontend/load_model.hpp"

namespace nhdyn::symbolic {
struct Spec;  // symbolic/spec.hpp (GiNaC): passed on by reference only
}

namespace nhdyn {

// The model's name ([model] name) and number of coordinates n.
const std::string& description_name(const symbolic::ModelDescription& description);
int description_coordinates(const symbolic::ModelDescription& description);

// Whether the model file gives its complement: independent coordinates (a partitioned D) or an
// analytic D.
bool description_gives_complement(const symbolic::ModelDescription& description);

// The Spec, for the functions of studies/ and symbolic/ that take one.
const symbolic::Spec& description_spec(const symbolic::ModelDescription& description);

// The equations of motion as `nhdyn equations` prints them (symbolic/equations.hpp,
// format_equations); derives the model on first use only.
std::string format_model_equations(const symbolic::ModelDescription& description, EquationsFormat format);

// Standalone C++ of the model in namespace `namespace_name` (symbolic/codegen.hpp, generate_code),
// and the identifier of its make_<identifier>_model() function.
std::string generate_model_code(const symbolic::ModelDescription& description, const std::string& namespace_name);
std::string model_code_identifier(const symbolic::ModelDescription& description);

// Per coordinate: it appears inside sin, cos or tan (symbolic/visual.hpp, VisualScene::angles);
// throws as compile_visual when a [visual] item does not compile.
const std::vector<bool>& description_angles(const symbolic::ModelDescription& description);

}  // namespace nhdyn
