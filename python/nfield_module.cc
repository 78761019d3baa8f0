// SPDX-License-Identifier: MIT
//
// The `nfield` Python module, a thin layer on the library:
//
//   f = nfield.load("out/poisson_2d/checkpoint.h5")   # the field of a checkpoint
//   u = f(x)                  # x: N × d points → N × m values
//   g = f.gradient(x)         # N × m × d: g[n, c, i] = ∂u_c/∂x_i
//   l = f.laplacian(x)        # N × m
//   s = f.streams(x, operators=[C], taylor_directions=W, taylor_order=4)  # autodiff/streams.h
//   metrics = nfield.run("configs/poisson_2d.yaml", set={"training.stages[0].steps": 50})
//   errors = f.evaluate("out/eval")   # as nfield eval: grid outputs, metrics.json as a dict
//
// Copies: points are read in place when they are a float64, Fortran-ordered (column-major)
// N × d array, the layout of the library's Eigen matrices (np.asfortranarray(x) makes one);
// any other array, C-ordered ones included, is copied once into that layout. A checkpoint
// with hard conditions (an ansatz u = A + D·N) copies the points once more, and its u streams
// are computed into a new block. The arrays returned are views into the one (S·N) × m
// column-major block a pass computes its streams in (stream s in rows [s·N, (s+1)·N)), which
// they keep alive: nothing is copied on the way out.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "fields/field_io.h"
#include "io/config.h"
#include "io/hdf5_file.h"
#include "io/version.h"
#include "solvers/core/solution.h"
#include "solvers/run/run.h"

namespace py = pybind11;

namespace nfield::python {
namespace {

using autodiff::StreamLayout;
using autodiff::StreamSpec;
using autodiff::Streams;
using FortranArray = py::array_t<double, py::array::f_style | py::array::forcecast>;

void require_file(const std::filesystem::path& path, const char* what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    const std::string message = path.string() + ": " + what + " not found";
    PyErr_SetObject(PyExc_FileNotFoundError,
                    py::make_tuple(ENOENT, message, path.string()).ptr());
    throw py::error_already_set();
  }
}

// A (rows × cols) float64 matrix argument in column-major order, converted only if needed.
FortranArray fortran_matrix(const py::handle& object, const char* name, py::ssize_t cols,
                            py::ssize_t rows = -1) {
  FortranArray a = FortranArray::ensure(object);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(std::string(name) + ": expected an array of numbers, got " +
                         std::string(py::str(py::type::of(object))));
  }
  if (a.ndim() != 2 || a.shape(1) != cols || (rows >= 0 && a.shape(0) != rows)) {
    std::ostringstream message;
    message << name << ": expected an array of shape (" << (rows >= 0 ? std::to_string(rows) : "N")
            << ", " << cols << "), got shape (";
    for (py::ssize_t k = 0; k < a.ndim(); ++k) message << (k ? ", " : "") << a.shape(k);
    message << (a.ndim() == 1 ? ",)" : ")");
    throw py::value_error(message.str());
  }
  return a;
}

Eigen::Map<const Eigen::MatrixXd> as_eigen(const FortranArray& a) {
  return {a.data(), a.shape(0), a.shape(1)};
}

// The streams of a pass as NumPy views: value (N, m), tangents (N, m, T), operators (N, m, Q),
// taylor (N, m, P, K) with taylor[..., p, k − 1] the k-th coefficient along direction p.
py::dict stream_arrays(Streams<double> computed, const StreamLayout& layout) {
  auto* streams = new Streams<double>(std::move(computed));
  const py::capsule owner(streams, [](void* p) { delete static_cast<Streams<double>*>(p); });
  const py::ssize_t n = streams->points, m = streams->width(), e = sizeof(double);
  const py::ssize_t column = e * n * streams->count;
  const auto view = [&](std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides,
                        int first_stream) {
    return py::array_t<double>(std::move(shape), std::move(strides),
                               streams->data.data() + first_stream * n, owner);
  };
  py::dict out;
  out["value"] = view({n, m}, {e, column}, layout.value());
  if (layout.tangents() > 0)
    out["tangents"] = view({n, m, layout.tangents()}, {e, column, e * n}, layout.tangent(0));
  if (layout.operators() > 0)
    out["operators"] = view({n, m, layout.operators()}, {e, column, e * n}, layout.op(0));
  if (layout.taylor_dirs() > 0)
    out["taylor"] = view({n, m, layout.taylor_dirs(), layout.taylor_order()},
                         {e, column, e * n * layout.taylor_order(), e * n}, layout.taylor(0, 1));
  return out;
}

// A checkpoint's field, evaluated in double (a float checkpoint converted on loading).
class CheckpointField {
 public:
  CheckpointField(const std::filesystem::path& path, bool ansatz) : path_(path) {
    require_file(path, "checkpoint");
    const io::H5Reader file(path);
    if (!file.has_group("field"))
      throw py::value_error(path.string() + ": not an nfield checkpoint (no group 'field')");
    field_ = std::make_unique<fields::Field<double>>(fields::load_field<double>(file));
    if (file.has_attribute("/", "config")) {
      config_ = file.read_attribute<std::string>("/", "config");
      if (ansatz) ansatz_ = solvers::load_checkpoint_run(file).problem->ansatz();
    }
  }

  int input_dim() const { return field_->input_dim(); }
  int output_dim() const { return field_->output_dim(); }

  py::dict streams(const py::handle& x, const StreamSpec& spec) const {
    const StreamLayout layout(spec);
    const FortranArray points = fortran_matrix(x, "points", input_dim());
    Streams<double> out;
    {
      py::gil_scoped_release unlocked;
      if (ansatz_) out = solvers::make_solution(*field_, ansatz_).streams(layout, as_eigen(points));
      else field_->evaluate(layout, as_eigen(points), out);  // in place, no copy
    }
    return stream_arrays(std::move(out), layout);
  }

  // Tangents along the axes unless given (d × T); operators T × T; Taylor directions d × P.
  StreamSpec spec(const py::object& tangents, const py::object& operators,
                  const py::object& taylor_directions, int taylor_order) const {
    const int d = input_dim();
    StreamSpec s = StreamSpec::gradient(d);
    if (!tangents.is_none()) {
      const FortranArray t = FortranArray::ensure(tangents);
      if (!t || t.ndim() != 2 || t.shape(0) != d)
        throw py::value_error("tangents: expected an array of shape (" + std::to_string(d) +
                              ", T), one direction a column");
      s.tangents = as_eigen(t);
    }
    const auto count = static_cast<py::ssize_t>(s.tangents.cols());
    // One T × T array, or a sequence of them (a 3-D array included).
    std::vector<py::object> matrices;
    if (py::isinstance<py::array>(operators) && operators.cast<py::array>().ndim() == 2)
      matrices.push_back(operators);
    else if (!operators.is_none())
      for (const py::handle c : operators)
        matrices.push_back(py::reinterpret_borrow<py::object>(c));
    for (size_t q = 0; q < matrices.size(); ++q)
      s.add_operator(as_eigen(fortran_matrix(
          matrices[q], ("operators[" + std::to_string(q) + "]").c_str(), count, count)));
    if (!taylor_directions.is_none()) {
      const FortranArray w = FortranArray::ensure(taylor_directions);
      if (!w || w.ndim() != 2 || w.shape(0) != d)
        throw py::value_error("taylor_directions: expected an array of shape (" +
                              std::to_string(d) + ", P), one direction a column");
      s.set_taylor(as_eigen(w), taylor_order);
    } else if (taylor_order != 0) {
      throw py::value_error("taylor_order: needs taylor_directions");
    }
    s.validate();
    return s;
  }

  std::string repr() const {
    return "<nfield.Field " + path_.string() + ": " + field_->options().type + ", " +
           std::to_string(input_dim()) + " → " + std::to_string(output_dim()) + ", " +
           std::to_string(field_->parameter_count()) + " parameters" +
           (ansatz_ ? ", hard-condition ansatz" : "") + ">";
  }

  std::filesystem::path path_;
  std::unique_ptr<fields::Field<double>> field_;
  std::shared_ptr<const solvers::Ansatz> ansatz_;
  std::string config_;
};

// `--set` assignments from a list of "key=value" strings or a mapping {key: value}.
std::vector<std::string> overrides(const py::object& set) {
  std::vector<std::string> out;
  if (set.is_none()) return out;
  if (py::isinstance<py::str>(set))
    throw py::type_error("set: expected a list of 'key=value' strings or a dict, got a string");
  if (py::isinstance<py::dict>(set)) {
    for (const auto& [key, value] : set.cast<py::dict>()) {
      // Python's True and None are YAML's true and null.
      const std::string text = py::isinstance<py::bool_>(value)
                                   ? (value.cast<bool>() ? "true" : "false")
                               : value.is_none() ? "null"
                                                 : std::string(py::str(value));
      out.push_back(std::string(py::str(key)) + "=" + text);
    }
    return out;
  }
  for (const py::handle item : set) {
    if (!py::isinstance<py::str>(item))
      throw py::type_error("set: expected 'key=value' strings, got " +
                           std::string(py::str(py::type::of(item))));
    out.push_back(item.cast<std::string>());
  }
  return out;
}

// nfield.DivergedError (a RuntimeError), set when the module loads; kept for the module's life.
PyObject* g_diverged_error = nullptr;

// out and resume are optional: a default path would reach Python as Path("."), not as empty.
py::object run(const std::filesystem::path& config, const py::object& set,
               const std::optional<std::filesystem::path>& out_dir,
               const std::optional<std::filesystem::path>& resume_from) {
  require_file(config, "config");
  const std::filesystem::path resume = resume_from.value_or(std::filesystem::path());
  solvers::RunSetup setup =
      solvers::load_run(config, overrides(set), out_dir.value_or(std::filesystem::path()));
  if (!resume.empty()) {
    require_file(resume, "checkpoint");
    if (!io::H5Reader(resume).has_group("field"))
      throw py::value_error(resume.string() + ": not an nfield checkpoint (no group 'field')");
  }
  int code;
  {
    py::gil_scoped_release unlocked;
    code = solvers::execute_run(setup, resume);
  }
  // metrics.json, as written: the run's own record is the one place its figures are named.
  std::ifstream in(setup.output.dir / "metrics.json");
  std::ostringstream text;
  text << in.rdbuf();
  const py::object metrics = py::module_::import("json").attr("loads")(text.str());
  if (code == 130) {
    PyErr_SetString(PyExc_KeyboardInterrupt,
                    ("run interrupted; checkpoint and outputs so far written to " +
                     setup.output.dir.string()).c_str());
    throw py::error_already_set();
  }
  if (code == solvers::kExitDiverged) {
    // The run's record goes with the error: where it stopped and what was written.
    const py::object error = py::reinterpret_borrow<py::object>(g_diverged_error)(
        metrics["stopped"].cast<std::string>() + "; checkpoint and outputs of the last finite state written to " +
        setup.output.dir.string());
    error.attr("metrics") = metrics;
    PyErr_SetObject(g_diverged_error, error.ptr());
    throw py::error_already_set();
  }
  return metrics;
}

}  // namespace
}  // namespace nfield::python

using namespace nfield;
using namespace nfield::python;

namespace {

// nfield.ConfigError, nfield.H5Error and nfield.DivergedError.
void add_exceptions(py::module_& m) {
  py::register_exception<io::ConfigError>(m, "ConfigError", PyExc_ValueError);
  py::register_exception<io::H5Error>(m, "H5Error", PyExc_OSError);
  g_diverged_error = PyErr_NewExceptionWithDoc(
      "nfield.DivergedError",
      "A run whose loss, gradient or update went non-finite (nfield run's exit code 3); its "
      "`metrics` attribute holds metrics.json (finished: false, stopped, divergence).",
      PyExc_RuntimeError, nullptr);
  m.attr("DivergedError") = py::handle(g_diverged_error);
}

// nfield.Field: a checkpoint's field evaluated at NumPy points.
void add_field_class(py::module_& m) {
  // The lambdas return py::object: an item accessor of the temporary dict would outlive it.
  const auto values = [](const CheckpointField& f, const py::handle& x) -> py::object {
    return f.streams(x, StreamSpec::values(f.input_dim()))["value"];
  };
  py::class_<CheckpointField>(m, "Field", "The field of a checkpoint, evaluated in double.")
      .def_property_readonly("input_dim", &CheckpointField::input_dim)
      .def_property_readonly("output_dim", &CheckpointField::output_dim)
      .def_property_readonly("parameter_count",
                             [](const CheckpointField& f) { return f.field_->parameter_count(); })
      .def_property_readonly("path", [](const CheckpointField& f) { return f.path_; })
      .def_property_readonly("config", [](const CheckpointField& f) { return f.config_; },
                             "The resolved config of the run that wrote the checkpoint (YAML).")
      .def_property_readonly("has_ansatz",
                             [](const CheckpointField& f) { return f.ansatz_ != nullptr; })
      .def(
          "evaluate",
          [](const CheckpointField& f, const std::filesystem::path& out, int grid) -> py::object {
            const auto metrics = solvers::evaluate_checkpoint(f.path_, grid, out);
            return py::module_::import("json").attr("loads")(metrics.dump());
          },
          py::arg("out"), py::arg("grid") = 64,
          "As `nfield eval CHECKPOINT --grid GRID --out OUT`: writes the grid outputs and "
          "metrics.json into out and returns metrics.json as a dict (a pde's reference.file "
          "errors under the run's keys: rel_l2, max_abs_err, max_abs_err_u, ...).")
      .def("values", values, py::arg("points"), "u at N × d points: N × m.")
      .def("__call__", values, py::arg("points"))
      .def(
          "gradient",
          [](const CheckpointField& f, const py::handle& x) -> py::object {
            return f.streams(x, StreamSpec::gradient(f.input_dim()))["tangents"];
          },
          py::arg("points"), "∂u_c/∂x_i at N × d points: N × m × d.")
      .def(
          "laplacian",
          [](const CheckpointField& f, const py::handle& x) -> py::object {
            return f.streams(x, StreamSpec::laplacian(f.input_dim()))["operators"]
                .attr("__getitem__")(py::make_tuple(py::ellipsis(), 0));
          },
          py::arg("points"), "Δu_c at N × d points: N × m.")
      .def(
          "streams",
          [](const CheckpointField& f, const py::handle& x, const py::object& tangents,
             const py::object& operators, const py::object& taylor_directions,
             int taylor_order) {
            return f.streams(x, f.spec(tangents, operators, taylor_directions, taylor_order));
          },
          py::arg("points"), py::kw_only(), py::arg("tangents") = py::none(),
          py::arg("operators") = py::none(),
          py::arg("taylor_directions") = py::none(), py::arg("taylor_order") = 0,
          "Derivative streams in one pass (autodiff/streams.h). tangents: d × T directions "
          "(default: the axes); operators: T × T symmetric matrices C, each giving "
          "Σ C_ij ∂²u/∂v_i∂v_j; taylor_directions: d × P, with taylor_order K. Returns a dict: "
          "'value' N × m, 'tangents' N × m × T, 'operators' N × m × Q, "
          "'taylor' N × m × P × K (coefficient k at index k − 1).")
      .def("__repr__", &CheckpointField::repr);
}

// nfield.load, nfield.validate, nfield.run.
void add_functions(py::module_& m) {
  m.def(
      "load",
      [](const std::filesystem::path& path, bool ansatz) {
        return CheckpointField(path, ansatz);
      },
      py::arg("checkpoint"), py::arg("ansatz") = true,
      "Loads the field of a checkpoint.h5 written by `nfield run`. With ansatz=True and hard "
      "conditions in its config, the field is u = A + D·N, as `nfield eval` writes it (the "
      "problem is rebuilt from the stored config, so its data files must be where the run "
      "read them); ansatz=False gives the network N itself.");
  m.def(
      "validate",
      [](const std::filesystem::path& config, const py::object& set) {
        require_file(config, "config");
        return io::to_yaml(solvers::load_run(config, overrides(set)).resolved);
      },
      py::arg("config"), py::arg("set") = py::none(),
      "Checks a config with `--set` overrides (a list of 'key=value' or a dict) and returns "
      "it resolved, as YAML text. A bad config raises nfield.ConfigError naming "
      "FILE:LINE:COL and the key.");
  m.def("run", &run, py::arg("config"), py::arg("set") = py::none(),
        py::arg("out") = py::none(), py::arg("resume") = py::none(),
        "Trains as `nfield run CONFIG --set ... --out OUT --resume CHECKPOINT` does, writes "
        "the outputs, and returns metrics.json as a dict. A bad config raises "
        "nfield.ConfigError before anything is written; a run that diverges (a non-finite "
        "step) raises nfield.DivergedError after writing its last finite state.");
}

}  // namespace

PYBIND11_MODULE(nfield, m) {
  m.doc() = "nfield: neural fields that solve PDEs. Evaluate checkpoints at NumPy points "
            "(values, gradients, Laplacians, any derivative stream) and run configs.";
  m.attr("__version__") = std::string(version());
  add_exceptions(m);
  add_field_class(m);
  add_functions(m);
}
