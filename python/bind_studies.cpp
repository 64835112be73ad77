// Python bindings: the studies, as the hooke command runs them; hooke/__init__.py reads
// their CSV tables back.

#include <string>
#include <utility>
#include <vector>

#include "experiments/cli.hpp"
#include "experiments/studies/crosscheck_command.hpp"
#include "experiments/studies/stability_map.hpp"
#include "experiments/studies/step_convergence_command.hpp"
#include "experiments/studies/work_precision.hpp"
#include "python/bindings.hpp"

namespace hooke::python {

void bind_studies(py::module_& m) {
  m.def(
      "_crosscheck",
      [](std::shared_ptr<Scene> scene, std::vector<std::string> methods, double rtol,
         const std::string& out) {
        CrosscheckOptions o;
        o.methods = std::move(methods);
        o.reference_rtol = rtol;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_crosscheck(*scene, o);
      },
      py::arg("scene"), py::arg("methods"), py::arg("reference_rtol"), py::arg("out"),
      "`hooke crosscheck` into the folder out; returns its exit code (see hooke.crosscheck).");
  m.def(
      "_stability",
      [](std::vector<std::string> cases, std::vector<std::string> methods, std::vector<double> k,
         bool full, bool plot, const std::string& out) {
        StabilityOptions o;
        o.cases = std::move(cases);
        o.methods = std::move(methods);
        o.k = std::move(k);
        o.full = full;
        o.plot = plot;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_stability(o, cli::scenes_dir().string());
      },
      py::arg("cases"), py::arg("methods"), py::arg("k"), py::arg("full"), py::arg("plot"),
      py::arg("out"),
      "`hooke stability` into the folder out; returns its exit code (see hooke.stability).");
  m.def(
      "_workprecision",
      [](std::vector<std::string> cases, std::vector<std::string> methods, int repeat, bool full,
         bool plot, const std::string& out) {
        WorkPrecisionOptions o;
        o.cases = std::move(cases);
        o.methods = std::move(methods);
        o.repeat = repeat;
        o.full = full;
        o.plot = plot;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_work_precision(o, cli::scenes_dir().string());
      },
      py::arg("cases"), py::arg("methods"), py::arg("repeat"), py::arg("full"), py::arg("plot"),
      py::arg("out"),
      "`hooke workprecision` into the folder out; returns its exit code (see "
      "hooke.workprecision).");
  m.def(
      "_step_convergence",
      [](const std::string& scene_path, bool full, const std::string& out) {
        StepConvergenceOptions o;
        o.full = full;
        o.out_dir = out;
        py::gil_scoped_release release;
        return run_step_convergence(scene_path, o);
      },
      py::arg("scene_path"), py::arg("full"), py::arg("out"),
      "`hooke step-convergence` into the folder out; returns its exit code (see "
      "hooke.step_convergence).");
}

}  // namespace hooke::python
