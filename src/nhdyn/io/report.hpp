// The HTML report of a run: one self-contained file (no server, no download when it is opened)
// with a 3-D animation of the motion, the plots of the run with a cursor at the current time, the
// summary and the model's equations rendered by KaTeX. Last stage of the pipeline, like the plots
// (io/plot.hpp): it reads the rows of a finished run (CSV layout of io/results.hpp) and, for the
// scene, the compiled visual tapes of the model (symbolic/visual.hpp), which it binds to the
// run's parameter values (parameters are data: a --set changes the drawn sizes and positions
// without recompiling anything) and runs on each row it shows. The JavaScript libraries (Debian's libjs-three and libjs-katex with its fonts) and
// the page's own template (io/resources/) are embedded in the library at build time; docs/report.md
// describes what the page shows and how long runs are thinned.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "nhdyn/io/csv.hpp"
#include "nhdyn/io/results.hpp"

#include "nhdyn/model/model.hpp"

namespace nhdyn::symbolic {
struct Spec;
class ModelDescription;  // symbolic/description.hpp (GiNaC), kept by frontend/load_model.hpp
struct VisualScene;
}

namespace nhdyn {

struct ReportInput {
  std::string title;                                         // e.g. "sled: sanh, dopri5"
  std::string model;                                         // the model's name
  std::vector<std::pair<std::string, std::string>> summary;  // label, value: the run's summary
  std::vector<std::string> coordinates;                      // the model's coordinates, in order
  std::vector<bool> angles;                                  // per coordinate: an angle (its own panel)
  ResultColumns columns;                                     // what each column of `table` is
  CsvTable table;                                            // the run, as written by simulate
  std::string equations_latex;  // an align* environment (symbolic/equations.hpp); "" when none
  std::string equations_note;   // shown instead of the equations when there are none, and why
  // The scene; null or without shapes: the path of `path` (else of the first two coordinates) is
  // drawn, and the page says the model has nothing to draw.
  const symbolic::VisualScene* scene = nullptr;
  // The run's parameter values, in the order of scene->parameters (Model::parameters): the scene's
  // tapes read them. Their names are checked against the scene's.
  std::vector<Parameter> parameters;
  std::optional<std::pair<std::string, std::string>> path;
  // The title of the panel of columns.actuators: program motion's actuator forces by default, an
  // optimum's controls (ReportOptions::controls) otherwise.
  std::string actuators_title = "actuator forces u ([[programs]])";
};

struct ReportOptions {
  // Most rows shown. A run of N rows shows every k-th row, k = ceil((N - 1) / (max_frames - 1)),
  // and always the last one; the CSV itself is never thinned. 2000 rows keep a 20 s run at 100
  // frames per second whole, and a page of any run under a few megabytes.
  int max_frames = 2000;
  // Equations longer than this (bytes of LaTeX) are left out with a note: KaTeX would take
  // seconds to lay out a bicycle's pages of terms, and `nhdyn equations` prints them anyway.
  std::size_t max_equations = 200000;
  // Columns after the model's own (make_result_columns), each plotted in one panel: the controls
  // u_NAME of `nhdyn optimize`, applied forces as program motion's actuators are.
  std::vector<std::string> controls;
};

// The one check of ReportOptions, for the command line (--max-frames) and Python (max_frames=)
// alike: InputError unless max_frames >= 2 (the first and the last row). write_model_report calls
// it; a caller may call it first to refuse the value before any work.
void check_report_options(const ReportOptions& options);

// Throws InputError when `header` is not the column layout `expected` (make_result_columns of the
// model): the message names the first column that differs, its position and what the model
// expects there, with the CSV's name `csv` and the model's name.
void check_report_columns(const std::vector<std::string>& header, const ResultColumns& expected,
                          const std::string& csv, const std::string& model);

// Throws InputError when the time column "t" of `table` (read from `csv`) holds a value that is not
// finite or is below the row above (an event row may share its time with an output row), naming
// the row and the value. A table without a "t" column passes (check_report_columns refuses it).
void check_report_times(const CsvTable& table, const std::string& csv);

// Throws InputError, naming the row, the column and the value, when a value of `table` outside the
// contact forces of `columns` (which are NaN where undetermined) is not finite: a run never writes
// one, so the CSV was edited or damaged, and its summary and scene would hide it (a NaN residual
// left out of a maximum, an energy drift of 0 from E0 = nan).
void check_report_values(const CsvTable& table, const ResultColumns& columns, const std::string& csv);

// The page as text. Throws InputError when the table has no row or its header is not
// input.columns.all, when input.parameters are not the scene's, or when a size of the scene is not
// positive with these values (naming the [visual] item, its place and the value). Same input -> same bytes. `notice`, when given, receives the note the page
// shows above the scene (nothing to draw, rows thinned), "" when none.
std::string make_report_html(const ReportInput& input, const ReportOptions& options = {}, std::string* notice = nullptr);

// make_report_html written through an AtomicFile (FileError when `path` cannot be written).
// Returns the page's notice ("" when none).
std::string write_report(const ReportInput& input, const std::filesystem::path& path, const ReportOptions& options = {});

// The report of a model's run, everything taken from the model: the columns it must have, its
// parameter values, its angles and scene (the description's, bound to model.parameters), its
// equations (from the description's derivation, the one the model was compiled from; none for a
// built-in model, whose description is null) and a summary computed from the rows (times,
// largest residual per level, energy drift), after `extra` (the run's own figures). Throws as
// check_report_columns when `table` is not this model's, InputError/ModelError for a scene that
// cannot be compiled, FileError when `path` cannot be written. Returns the page's notice for the
// user ("" when none): the model has nothing to draw, or the rows were thinned.
std::string write_model_report(const Model& model, const symbolic::ModelDescription* description, const CsvTable& table, const std::string& title,
                        const std::vector<std::pair<std::string, std::string>>& extra,
                        const std::filesystem::path& path, const ReportOptions& options = {});

// The same for a Spec built in C++ (symbolic/spec_builder.hpp) with no description kept: the
// description is made here, so the equations are derived and the scene compiled for this page.
std::string write_model_report(const Model& model, const symbolic::Spec* spec, const CsvTable& table,
                               const std::string& title, const std::vector<std::pair<std::string, std::string>>& extra,
                               const std::filesystem::path& path, const ReportOptions& options = {});

// The rows a report shows out of `rows` (indices, ascending, first and last included).
std::vector<std::size_t> report_frames(std::size_t rows, int max_frames);

// The scene's sizes for the given parameter values (in the order of scene.parameters), per shape:
// sphere and wheel (r, r, r); body the semi-axes of its equivalent ellipsoid of inertia (uniform
// solid ellipsoid of the same mass and inertia, a_i^2 = 5 (I_j + I_k - I_i) / (2 m), along the
// columns of `axes`, its principal directions in the body frame's components, 9 numbers row-major);
// segment and frame (0, 0, 0). Throws InputError as make_report_html for a radius that is not
// positive or parameters that are not the scene's.
struct SceneSize {
  std::array<double, 3> size = {0.0, 0.0, 0.0};
  std::array<double, 9> axes = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};
std::vector<SceneSize> calc_scene_sizes(const symbolic::VisualScene& scene, const std::vector<Parameter>& parameters,
                                        const std::string& model);
// (calc_scene_sizes also gives: ellipsoid its semi-axes (a, b, c) along the frame's axes; torus
// (R, r, 0); solid, track, terrain and surface (0, 0, 0), their extent being their mesh's or path's.)

// The triangle meshes of the scene's solid, terrain and surface shapes for the given parameter
// values, computed once per report from `values` (the scene tape's outputs at the frames
// drawn, `stride` per frame): a solid's zero set f = 0 in its frame's axes, sampled along 25 x 49
// rays from its centre (f < 0 there; bisection to round-off), spread as the unit sphere stretched
// by the shape's reach along each axis; a terrain's height h(X, Y) at the
// nodes of a grid of 49 x 49 (at most) over the region its contact point covers, widened by a
// margin (a third of the region's width, at least four lengths of the shape); a surface's zero
// set g = 0 along rays from the point inside it (a sphere's centre; for any other surface a
// point where g < 0 below the mean of the contact's path along its normal), over the cap that
// the contact point's directions from there cover, widened by the same margin, or else over its
// tangent plane there. Empty for the other kinds, and for a surface that none of these draws
// (then `notes`, when given, gets a sentence that says so). Throws InputError naming the contact
// when a solid's f is not negative at its centre or a ray meets no zero of f or of a sphere's g.
struct SceneMesh {
  std::vector<double> vertices;  // x, y, z per vertex (solid: the frame's axes; terrain, surface: world)
  std::vector<int> triangles;    // three vertex indices each, two per cell of the grid
  int rows = 0;                  // the vertices are a grid of `rows` rows, row-major (lines drawn along it)
};
std::vector<SceneMesh> calc_scene_meshes(const symbolic::VisualScene& scene, const std::vector<Parameter>& parameters,
                                         const std::vector<double>& values, std::size_t stride, const std::string& model,
                                         std::vector<std::string>* notes = nullptr);

}  // namespace nhdyn
