# SPDX-License-Identifier: MIT
"""The Python module against the library: derivatives of a checkpoint's field against finite
differences, a run returning its metrics, and the exceptions bad input raises. CTest runs each
class with PYTHONPATH at the built module (python/CMakeLists.txt)."""
import json
import os
import tempfile
import unittest

import numpy as np

import nfield

HERE = os.path.dirname(os.path.abspath(__file__))
TINY = os.path.join(HERE, "tiny_poisson.yaml")


def train(out, *assignments):
    return nfield.run(TINY, set=["training.stages[0].steps=5", *assignments], out=out)


class FieldTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        soft, hard = os.path.join(cls.tmp.name, "soft"), os.path.join(cls.tmp.name, "hard")
        train(soft)
        # The same problem with u = 0 enforced exactly: u = φ·N, φ vanishing on the boundary.
        train(hard, 'conditions=[{on: boundary, type: dirichlet, value: "0", enforce: hard}]')
        cls.field = nfield.load(os.path.join(soft, "checkpoint.h5"))
        cls.hard = nfield.load(os.path.join(hard, "checkpoint.h5"))
        cls.network = nfield.load(os.path.join(hard, "checkpoint.h5"), ansatz=False)
        rng = np.random.default_rng(1)
        cls.x = np.asfortranarray(rng.uniform(0.1, 0.9, size=(7, 2)))

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def differences(self, f, h):
        """Central differences of u at self.x: gradient (N, m, d) and Laplacian (N, m)."""
        u = f(self.x)
        gradient = np.empty(u.shape + (2,))
        laplacian = -4 * u
        for i in range(2):
            step = np.zeros(2)
            step[i] = h
            plus, minus = f(self.x + step), f(self.x - step)
            gradient[:, :, i] = (plus - minus) / (2 * h)
            laplacian += plus + minus
        return gradient, laplacian / h**2

    def test_shapes(self):
        f = self.field
        self.assertEqual((f.input_dim, f.output_dim), (2, 1))
        self.assertEqual(f.values(self.x).shape, (7, 1))
        self.assertEqual(f.gradient(self.x).shape, (7, 1, 2))
        self.assertEqual(f.laplacian(self.x).shape, (7, 1))
        self.assertIn("problem: poisson", f.config)
        self.assertFalse(f.has_ansatz)

    def test_gradient_and_laplacian_match_differences(self):
        for f in (self.field, self.hard):
            gradient, _ = self.differences(f, 1e-5)
            _, laplacian = self.differences(f, 1e-3)
            np.testing.assert_allclose(f.gradient(self.x), gradient, rtol=1e-6, atol=1e-7)
            np.testing.assert_allclose(f.laplacian(self.x), laplacian, rtol=1e-4, atol=1e-4)

    def test_operator_and_taylor_streams_match_differences(self):
        # C = (e_x e_yᵀ + e_y e_xᵀ)/2 gives ∂²u/∂x∂y; a Taylor series of order 2 along w gives
        # (1/2) d²u/dτ² at x + τw.
        w = np.array([[0.6], [0.8]])
        s = self.field.streams(self.x, operators=[[[0, 0.5], [0.5, 0]]], taylor_directions=w,
                               taylor_order=2)
        self.assertEqual(s["operators"].shape, (7, 1, 1))
        self.assertEqual(s["taylor"].shape, (7, 1, 1, 2))
        h = 1e-3
        f = self.field
        mixed = (f(self.x + [h, h]) - f(self.x + [h, -h]) - f(self.x + [-h, h])
                 + f(self.x - [h, h])) / (4 * h * h)
        along = w[:, 0] * h
        second = (f(self.x + along) - 2 * f(self.x) + f(self.x - along)) / (h * h)
        np.testing.assert_allclose(s["operators"][:, :, 0], mixed, rtol=1e-4, atol=1e-4)
        np.testing.assert_allclose(2 * s["taylor"][:, :, 0, 1], second, rtol=1e-4, atol=1e-4)
        np.testing.assert_allclose(s["taylor"][:, :, 0, 0],
                                   f.gradient(self.x)[:, :, :] @ w[:, 0], rtol=1e-12)

    def test_streams_are_views_of_one_block(self):
        s = self.field.streams(self.x, operators=np.eye(2))
        self.assertIs(s["value"].base, s["tangents"].base)
        self.assertIs(s["value"].base, s["operators"].base)
        np.testing.assert_allclose(s["operators"][:, :, 0], self.field.laplacian(self.x))

    def test_c_ordered_and_list_points_give_the_same_values(self):
        expected = self.field(self.x)
        np.testing.assert_array_equal(self.field(np.ascontiguousarray(self.x)), expected)
        np.testing.assert_array_equal(self.field(self.x.tolist()), expected)
        np.testing.assert_array_equal(self.field(self.x.astype(np.float32)),
                                      self.field(self.x.astype(np.float32).astype(float)))

    def test_ansatz_vanishes_on_the_boundary(self):
        self.assertTrue(self.hard.has_ansatz)
        edge = np.array([[0.0, 0.3], [1.0, 0.7], [0.4, 0.0], [0.5, 1.0]])
        np.testing.assert_allclose(self.hard(edge), 0, atol=1e-14)
        self.assertGreater(np.abs(self.network(edge)).max(), 1e-6)


class RunTest(unittest.TestCase):
    def test_run_returns_its_metrics(self):
        with tempfile.TemporaryDirectory() as out:
            metrics = nfield.run(TINY, set={"training.stages[0].steps": 7, "output.png": False},
                                 out=out)
            with open(os.path.join(out, "metrics.json")) as f:
                self.assertEqual(metrics, json.load(f))
            self.assertEqual(metrics["problem"], "poisson")
            self.assertEqual(metrics["steps"], 7)
            self.assertTrue(metrics["finished"])
            self.assertGreater(metrics["rel_l2"], 0)
            self.assertEqual([s["optimizer"] for s in metrics["stages"]], ["adam"])
            resumed = nfield.run(TINY, set=["training.stages[0].steps=7"], out=out,
                                 resume=os.path.join(out, "checkpoint.h5"))
            self.assertTrue(resumed["finished"])
            with self.assertRaises(nfield.H5Error):
                nfield.run(TINY, out=out, resume=TINY)

    def test_parametric_field_takes_the_parameter_as_a_column(self):
        """A constant given as a range is the field's third input (x, t, nu)."""
        with tempfile.TemporaryDirectory() as tmp:
            config = os.path.join(tmp, "family.yaml")
            with open(config, "w") as f:
                f.write("problem: pde\n"
                        "domain: {lower: [-1], upper: [1], time: [0, 1]}\n"
                        "constants: {nu: {range: [0.01, 0.05]}}\n"
                        "equation: {residuals: [\"u_t + u*u_x - nu*u_xx\"]}\n"
                        "conditions: [{on: initial, type: value, value: \"-sin(pi*x)\", enforce: hard}]\n"
                        "reference: {solution: burgers_sine, nu: nu, held_out: {nu: [0.02, 0.04]}}\n"
                        "field: {type: mlp, hidden: [8, 8]}\n"
                        "training: {threads: 1, batch: {interior: 32}, stages: [{optimizer: adam, steps: 3}]}\n"
                        "output: {grid: [9], frames: 3, png: false}\n")
            metrics = nfield.run(config, out=os.path.join(tmp, "out"))
            self.assertEqual([h["nu"] for h in metrics["held_out"]], [0.02, 0.04])
            f = nfield.load(os.path.join(tmp, "out", "checkpoint.h5"))
            self.assertEqual(f.input_dim, 3)
            x = np.array([[0.3, 0.0, 0.02], [0.3, 0.0, 0.04], [0.3, 1.0, 0.02], [0.3, 1.0, 0.04]])
            u = f.values(x)
            # t = 0: the hard initial value whatever nu; t = 1: the network reads the column.
            self.assertAlmostEqual(u[0, 0], -np.sin(np.pi * 0.3), places=12)
            self.assertAlmostEqual(u[1, 0], -np.sin(np.pi * 0.3), places=12)
            self.assertNotEqual(u[2, 0], u[3, 0])
            with self.assertRaises(ValueError):
                f.values(x[:, :2])

    def test_divergence_raises_with_the_metrics(self):
        with tempfile.TemporaryDirectory() as out:
            with self.assertRaisesRegex(nfield.DivergedError, r"^diverged: step \d+ \(stage 1, adam\)") as raised:
                nfield.run(TINY, set={"training.stages[0].lr": 1e30, "training.precision": "float",
                                      "training.stages[0].steps": 200,
                                      "output.png": False}, out=out)
            self.assertIsInstance(raised.exception, RuntimeError)
            metrics = raised.exception.metrics
            self.assertFalse(metrics["finished"])
            self.assertEqual(metrics["divergence"]["optimizer"], "adam")
            self.assertTrue(os.path.exists(os.path.join(out, "checkpoint.h5")))

    def test_validate_resolves_overrides(self):
        text = nfield.validate(TINY, set={"training.seed": 4})
        self.assertIn("seed: 4", text)
        self.assertIn("steps: 20", text)


class ReferenceTest(unittest.TestCase):
    """A pde run compared with a reference.file (a derived quantity in one CSV, an output in
    another): the loaded field's errors at the files' points, by NumPy, are metrics.json's, and
    Field.evaluate (nfield eval) returns the same; a file gone is the located config error."""

    CONFIG = """problem: pde
domain: {lower: [0, 0], upper: [1, 1]}
outputs: [a, b]
derived: {s: "a + x"}
equation:
  residuals:
    - {name: fa, expr: "a - x*y"}
    - {name: fb, expr: "b - y^2"}
reference:
  file:
    - {file: data/s.csv, outputs: [s]}
    - {file: data/b.csv, outputs: [b]}
field: {type: siren, hidden: [8, 8], first_omega: 3, hidden_omega: 1}
training: {threads: 1, precision: double, batch: {interior: 32},
           stages: [{optimizer: adam, steps: 20, lr: 1.0e-2}]}
output: {grid: [5, 5], png: false}
"""

    def test_errors_of_the_loaded_field_are_the_runs(self):
        with tempfile.TemporaryDirectory() as tmp:
            os.makedirs(os.path.join(tmp, "data"))
            y = 0.1 * (np.arange(9) + 0.5)
            s_points = np.column_stack([np.full(9, 0.5), y, 0.5 * y + 0.5])
            b_points = np.column_stack([y, np.full(9, 0.5), np.full(9, 0.25)])
            np.savetxt(os.path.join(tmp, "data", "s.csv"), s_points, delimiter=",", header="x,y,s",
                       comments="")
            np.savetxt(os.path.join(tmp, "data", "b.csv"), b_points, delimiter=",", header="x,y,b",
                       comments="")
            config = os.path.join(tmp, "pde.yaml")
            with open(config, "w") as f:
                f.write(self.CONFIG)
            out = os.path.join(tmp, "out")
            ran = nfield.run(config, out=out)
            field = nfield.load(os.path.join(out, "checkpoint.h5"))
            s = field(s_points[:, :2])[:, 0] + s_points[:, 0]
            b = field(b_points[:, :2])[:, 1]
            self.assertAlmostEqual(ran["max_abs_err_s"], np.max(np.abs(s - s_points[:, 2])), delta=1e-12)
            self.assertAlmostEqual(ran["max_abs_err_b"], np.max(np.abs(b - b_points[:, 2])), delta=1e-12)
            self.assertGreater(ran["max_abs_err_s"], 0)
            evaluated = field.evaluate(os.path.join(tmp, "ev"), grid=5)
            for key in ("rel_l2", "max_abs_err", "rel_l2_s", "max_abs_err_s", "rel_l2_b",
                        "max_abs_err_b", "reference_points"):
                self.assertAlmostEqual(evaluated[key], ran[key], delta=1e-12 * ran[key], msg=key)
            os.remove(os.path.join(tmp, "data", "b.csv"))
            with self.assertRaisesRegex(nfield.ConfigError, r"reference\.file.*b\.csv"):
                nfield.load(os.path.join(out, "checkpoint.h5"))
            self.assertEqual(nfield.load(os.path.join(out, "checkpoint.h5"), ansatz=False).output_dim, 2)


class ErrorsTest(unittest.TestCase):
    def test_bad_config_raises_the_located_message(self):
        with self.assertRaises(nfield.ConfigError) as raised:
            nfield.run(os.path.join(HERE, "bad_stage.yaml"))
        self.assertRegex(str(raised.exception),
                         r"bad_stage\.yaml:12:32: training\.stages\[0\]\.steps: expected an "
                         r"integer in \[0, \d+\], got '-3'")
        self.assertIsInstance(raised.exception, ValueError)

    def test_bad_override_raises(self):
        with self.assertRaisesRegex(nfield.ConfigError, r"unknown key 'stepz'"):
            nfield.validate(TINY, set=["training.stages[0].stepz=3"])
        with self.assertRaisesRegex(TypeError, "got a string"):
            nfield.validate(TINY, set="training.seed=3")

    def test_missing_files(self):
        with self.assertRaisesRegex(FileNotFoundError, "nowhere.yaml: config not found"):
            nfield.run("nowhere.yaml")
        with self.assertRaisesRegex(FileNotFoundError, "nowhere.h5: checkpoint not found"):
            nfield.load("nowhere.h5")

    def test_a_file_that_is_no_checkpoint(self):
        with self.assertRaises(nfield.H5Error):
            nfield.load(TINY)

    def test_wrong_points(self):
        with tempfile.TemporaryDirectory() as out:
            train(out)
            f = nfield.load(os.path.join(out, "checkpoint.h5"))
        with self.assertRaisesRegex(ValueError,
                                    r"points: expected an array of shape \(N, 2\), got shape "
                                    r"\(5, 3\)"):
            f(np.zeros((5, 3)))
        with self.assertRaisesRegex(ValueError, r"got shape \(4,\)"):
            f.gradient(np.zeros(4))
        with self.assertRaisesRegex(TypeError, "expected an array of numbers"):
            f.laplacian([["a", "b"]])
        with self.assertRaisesRegex(ValueError, r"operators\[0\]: expected an array of shape "
                                                r"\(2, 2\), got shape \(3, 3\)"):
            f.streams(np.zeros((1, 2)), operators=[np.eye(3)])


if __name__ == "__main__":
    unittest.main()
