// SPDX-License-Identifier: MIT
//
// Bad input to the nfield program: every broken config is refused by `nfield validate` and
// `nfield run` alike with exit code 2 and one line on stderr,
//   nfield: error: FILE:LINE:COL: KEY.PATH: what was expected
// and nothing is written (no output folder, not even the one --out names). Also bad
// command lines (missing files, bad options) and the help texts.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "cli_test_support.h"
#include "io/hdf5_file.h"

namespace nfield::apps::testing {
namespace {

// A small, valid Poisson config; the cases below break one thing in it.
constexpr const char* kBase =
    "problem: poisson\n"                                   // 1
    "domain:\n"                                            // 2
    "  lower: [0, 0]\n"                                    // 3
    "  upper: [1, 1]\n"                                    // 4
    "equation:\n"                                          // 5
    "  source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\"\n"          // 6
    "  exact: \"sin(pi*x)*sin(pi*y)\"\n"                   // 7
    "conditions:\n"                                        // 8
    "  - {on: boundary, type: dirichlet, value: \"0\"}\n"  // 9
    "field:\n"                                             // 10
    "  type: siren\n"                                      // 11
    "  hidden: [8, 8]\n"                                   // 12
    "  first_omega: 3\n"                                   // 13
    "  hidden_omega: 1\n"                                  // 14
    "training:\n"                                          // 15
    "  seed: 0\n"                                          // 16
    "  precision: double\n"                                // 17
    "  threads: 1\n"                                       // 18
    "  batch: {interior: 32, boundary: 16}\n"              // 19
    "  stages:\n"                                          // 20
    "    - {optimizer: adam, steps: 3, lr: 1.0e-3}\n"      // 21
    "output:\n"                                            // 22
    "  grid: [5, 5]\n";                                    // 23

// kBase with the one occurrence of `from` replaced by `to`.
std::string edit(const std::string& from, const std::string& to, std::string text = kBase) {
  const std::size_t at = text.find(from);
  if (at == std::string::npos || text.find(from, at + 1) != std::string::npos)
    throw std::logic_error("edit: '" + from + "' is not in the config exactly once");
  return text.replace(at, from.size(), to);
}

const std::string kNerfTrain =
    "  train: " NFIELD_SOURCE_DIR "/data/multiview/bunny_blender/transforms_train.json\n";

// A radiance-field config with the given `data:` entries and `render:` extras.
std::string nerf(const std::string& data, const std::string& render = "") {
  return "problem: nerf\ndata:\n" + data +
         "scene: {lower: [-0.6, -0.6, -0.6], upper: [0.6, 0.6, 0.6]}\n"
         "render:\n  samples: 8\n" + render +
         "field: {type: nerf, hidden: [8], color_hidden: [8]}\n"
         "training:\n  batch: {rays: 16}\n  stages: [{optimizer: adam, steps: 2, lr: 1.0e-3}]\n";
}

struct BadConfig {
  std::string name;
  std::string yaml;
  // Where the error points: a text that occurs once in `yaml`, with '|' at the reported
  // character ("lr: |fast"). Empty: the message names no line and column.
  std::string at;
  std::string key_path;               // "" when the message names none
  std::vector<std::string> expected;  // further parts of the message
  std::vector<std::string> args = {}; // after CONFIG (e.g. --set k=v)
  std::string file = {};              // the place named instead of the config file
};

void PrintTo(const BadConfig& c, std::ostream* out) { *out << c.name; }

// "LINE:COL" of the '|' in `at` within `yaml`.
std::string location(const BadConfig& c) {
  const std::size_t bar = c.at.find('|');
  const std::string text = c.at.substr(0, bar) + c.at.substr(bar + 1);
  const std::size_t start = c.yaml.find(text);
  if (bar == std::string::npos || start == std::string::npos ||
      c.yaml.find(text, start + 1) != std::string::npos)
    throw std::logic_error(c.name + ": 'at' must occur once in the config and hold one '|'");
  const std::size_t position = start + bar;
  const std::string before = c.yaml.substr(0, position);
  const auto line = std::count(before.begin(), before.end(), '\n');
  const std::size_t newline = before.rfind('\n');
  const std::size_t column = newline == std::string::npos ? position : position - newline - 1;
  return std::to_string(line + 1) + ":" + std::to_string(column + 1);
}

// `text` (kBase or an edit of it) as a `problem: pde` config: the same equation as a residual.
std::string pde(const std::string& text) {
  std::string out = edit("problem: poisson", "problem: pde", text);
  return edit("  source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\"\n  exact: \"sin(pi*x)*sin(pi*y)\"\n",
              "  residuals: [\"lap(u) + 2*pi^2*sin(pi*x)*sin(pi*y)\"]\n", out);
}

std::vector<BadConfig> bad_configs() {
  const std::string base = kBase;
  return {
      // Unknown keys, at every level.
      {"UnknownTopLevelKey", base + "solver: fast\n", "|solver", "solver",
       {"unknown key 'solver' (valid keys: ", "problem", "domain", "training", "output"}},
      {"UnknownStageKey", edit("lr: 1.0e-3}", "lrr: 1.0e-3}"), "|lrr", "training.stages[0].lrr",
       {"unknown key 'lrr' (valid keys: optimizer, steps, batch_scale, lr, schedule, lr_final, seconds)"}},
      {"UnknownFieldKey", edit("  hidden: [8, 8]", "  hiden: [8, 8]"), "|hiden", "field.hiden",
       {"unknown key 'hiden'", "hidden"}},
      {"UnknownConditionKey", edit("value: \"0\"}", "value: \"0\", wieght: 2}"), "|wieght",
       "conditions[0].wieght", {"unknown key 'wieght'", "weight"}},
      {"UnknownDomainKey", edit("  upper: [1, 1]\n", "  upper: [1, 1]\n  tme: [0, 1]\n"), "|tme",
       "domain.tme", {"unknown key 'tme'", "time"}},
      {"UnknownOutputKey", base + "  every: 3\n", "|every", "output.every",
       {"unknown key 'every'", "grid", "frames"}},
      {"UnknownEquationKey", edit("  exact:", "  exakt:"), "|exakt", "equation.exakt",
       {"unknown key 'exakt'", "source", "exact"}},
      // Wrong types.
      {"StringForNumber", edit("lr: 1.0e-3", "lr: fast"), "lr: |fast", "training.stages[0].lr",
       {"expected a number, got 'fast'"}},
      {"QuotedStringForInteger", edit("steps: 3", "steps: \"three\""), "steps: |\"three\"",
       "training.stages[0].steps", {"expected an integer, got 'three'"}},
      {"FractionForInteger", edit("threads: 1", "threads: 1.5"), "threads: |1.5",
       "training.threads", {"expected an integer, got '1.5'"}},
      {"ScalarForList", edit("hidden: [8, 8]", "hidden: 8"), "hidden: |8", "field.hidden",
       {"expected a list of integers, got '8'"}},
      {"MappingForConditions", edit("  - {on: boundary, type: dirichlet, value: \"0\"}",
                                    "  {on: boundary, type: dirichlet, value: \"0\"}"),
       "  |{on: boundary", "conditions", {"expected a list of conditions"}},
      // Values out of range.
      {"NegativeSteps", edit("steps: 3", "steps: -5"), "steps: |-5", "training.stages[0].steps",
       {"expected an integer in [0, 1073741824], got '-5'"}},
      {"ZeroLearningRate", edit("lr: 1.0e-3", "lr: 0"), "lr: |0", "training.stages[0].lr",
       {"expected a learning rate > 0"}},
      {"GridOfOnePoint", edit("grid: [5, 5]", "grid: [1, 5]"), "grid: |[1, 5]", "output.grid",
       {"expected point counts in [2, 4096]"}},
      {"NegativeThreads", edit("threads: 1", "threads: -1"), "threads: |-1", "training.threads",
       {"expected an integer in [0, 1024], got '-1'"}},
      {"ZeroWidth", edit("hidden: [8, 8]", "hidden: [8, 0]"), "hidden: |[8, 0]", "field.hidden",
       {"expected widths in [1, 16384]"}},
      {"EmptyStages", edit("    - {optimizer: adam, steps: 3, lr: 1.0e-3}\n", "    []\n"),
       "    |[]", "training.stages", {"expected a non-empty list of stages"}},
      // Batch entries are point kinds: a misspelled one is an error.
      {"MisspelledBatchKey", edit("batch: {interior: 32,", "batch: {interor: 32,"),
       "batch: {|interor", "training.batch.interor",
       {"unknown key 'interor' (valid keys: interior, boundary, initial)"}},
      {"MisspelledBoundaryBatchKey", edit("boundary: 16}", "boundry: 16}"), "|boundry: 16",
       "training.batch.boundry",
       {"unknown key 'boundry' (valid keys: interior, boundary, initial)"}},
      // Lists of the wrong length.
      {"UpperLongerThanLower", edit("upper: [1, 1]", "upper: [1, 1, 1]"), "upper: |[1, 1, 1]",
       "domain.upper", {"expected a list of 2 numbers, got a list of 3"}},
      {"GridOfWrongLength", edit("grid: [5, 5]", "grid: [5]"), "grid: |[5]", "output.grid",
       {"expected a list of 2 integers, got a list of 1"}},
      // Unknown choices: the message lists the valid ones.
      {"BadOptimizer", edit("optimizer: adam", "optimizer: adamw"), "optimizer: |adamw",
       "training.stages[0].optimizer", {"expected one of adam, lbfgs, lm; got 'adamw'"}},
      {"BadProblem", edit("problem: poisson", "problem: poison"), "problem: |poison", "problem",
       {"expected one of ", "poisson", "wave", "; got 'poison'"}},
      {"BadFieldType", edit("type: siren", "type: sirenn"), "type: |sirenn", "field.type",
       {"expected one of acorn, bacon, mlp, nerf, siren; got 'sirenn'"}},
      // A field type without the streams the equation needs: refused at its type, not mid-run.
      {"AcornForTheLaplacian",
       edit("  type: siren\n  hidden: [8, 8]\n  first_omega: 3\n  hidden_omega: 1\n",
            "  type: acorn\n  hidden: [8]\n"),
       "type: |acorn", "field.type",
       {"'acorn' gives the value and gradient (tangent) streams only", "the loss term 'pde' needs them"}},
      {"BadActivation", edit("type: siren", "type: mlp\n  activation: swish"), "activation: |swish",
       "field.activation", {"expected one of ", "relu", "sine", "softplus", "tanh", "; got 'swish'"}},
      {"BadEncoding", edit("  hidden_omega: 1\n", "  hidden_omega: 1\n  encoding: {type: hash}\n"),
       "type: |hash", "field.encoding.type",
       {"expected one of ", "fourier", "identity", "positional", "; got 'hash'"}},
      {"BadPrecision", edit("precision: double", "precision: half"), "precision: |half",
       "training.precision", {"expected one of float, double; got 'half'"}},
      {"BadSchedule", edit("lr: 1.0e-3}", "lr: 1.0e-3, schedule: linear}"), "schedule: |linear",
       "training.stages[0].schedule", {"expected one of constant, cosine, exponential; got 'linear'"}},
      // A radiance field: its data files and its sections.
      {"NerfMissingTransforms", nerf("  train: missing/transforms.json\n"), "train: |missing",
       "data.train", {"missing/transforms.json"}},
      {"NerfBadBackground", nerf(kNerfTrain + "  background: grey\n"), "background: |grey",
       "data.background", {"expected one of white, black, random; got 'grey'"}},
      {"NerfUnknownOccupancyKey", nerf(kNerfTrain, "  occupancy: {resolution: 32, evry: 4}\n"),
       "32, |evry", "render.occupancy.evry", {"unknown key 'evry'", "every"}},
      // Expressions.
      {"UnbalancedExpression", edit("-2*pi^2*sin(pi*x)*sin(pi*y)", "-2*pi^2*sin(pi*x"),
       // muparser gives no position for a missing parenthesis: the value's start.
       "source: |\"-2*pi^2*sin(pi*x\"", "equation.source",
       {"in expression '-2*pi^2*sin(pi*x'", "parenthesis"}},
      {"UnknownVariable", edit("exact: \"sin(pi*x)*sin(pi*y)\"", "exact: \"sin(pi*q)*sin(pi*y)\""),
       "exact: \"sin(pi*|q)", "equation.exact", {"in expression 'sin(pi*q)*sin(pi*y)'", "\"q\""}},
      {"BadExpressionInValueList", edit("value: \"0\"}", "value: [\"sin(pi*x\"]}"),
       "value: [|\"sin(pi*x\"]", "conditions[0].value[0]", {"in expression 'sin(pi*x'"}},
      // Missing required keys.
      {"MissingProblem", edit("problem: poisson\n", ""), "|domain:", "problem",
       {"missing required key 'problem'"}},
      {"MissingDomain", edit("domain:\n  lower: [0, 0]\n  upper: [1, 1]\n", ""), "|problem",
       "domain",
       {"missing required key 'domain'"}},
      {"MissingSource", edit("  source: \"-2*pi^2*sin(pi*x)*sin(pi*y)\"\n", ""), "  |exact",
       "equation.source", {"missing required key 'source'"}},
      // A file without keys is still a place: its start.
      {"EmptyFile", "", "|", "problem", {"missing required key 'problem'"}},
      // Conditions.
      {"BadFaceName", edit("on: boundary", "on: w_min"), "on: |w_min", "conditions[0].on",
       {"unknown face 'w_min' (valid: x_max, x_min, y_max, y_min), or boundary, initial"}},
      {"EmptyFaceList", edit("on: boundary", "on: []"), "on: |[]", "conditions[0].on",
       {"expected a face name"}},
      {"InitialWithoutTime", edit("on: boundary, type: dirichlet", "on: initial, type: value"),
       "on: |initial", "conditions[0].on", {"'initial' needs a domain with a time interval"}},
      // problem: pde: conditions by name and reference.file.
      {"PdeConditionUnknownOutput", pde(edit("value: \"0\"}", "value: {w: \"0\"}}")), "{w: |\"0\"}",
       "conditions[0].value.w", {"'w' is no output (outputs: u)"}},
      {"PdePeriodicNotOpposite", pde(edit("type: dirichlet, value: \"0\"", "type: periodic")),
       "on: |boundary", "conditions[0].on", {"a periodic condition pairs two opposite faces of one axis"}},
      {"PdeReferenceFileMissing", pde(base) + "reference: {file: missing.csv}\n", "file: |missing.csv",
       "reference.file", {"missing.csv: no such file"}},
      // problem: pde, inverse problems: unknown constants and measurements.
      {"PdeTruthOfKnownConstant", pde(base) + "constants:\n  k: {unknown: false, true: 2}\n", "true: |2}",
       "constants.k.true", {"'true' is the truth of an unknown constant; 'k' is known"}},
      {"PdeUnknownBoundsReversed", pde(base) + "constants:\n  k: {unknown: true, initial: 1, bounds: [3, 2]}\n",
       "bounds: |[3, 2]", "constants.k.bounds", {"expected [lower, upper] with lower < upper"}},
      {"PdeUnknownInitialOutsideBounds", pde(base) + "constants:\n  k: {unknown: true, initial: 5, bounds: [1, 2]}\n",
       "initial: |5", "constants.k.initial", {"strictly inside bounds [1, 2]"}},
      {"PdeUnknownPositiveInitialZero", pde(base) + "constants:\n  k: {unknown: true, initial: 0, positive: true}\n",
       "initial: |0", "constants.k.initial", {"expected an initial value > 0 (positive: true)"}},
      {"PdeDataFileMissing", pde(base) + "data: {file: missing.csv}\n", "file: |missing.csv", "data.file",
       {"missing.csv: no such file"}},
      {"PdeDataUnknownOutput", pde(base) + "data: {exact: {w: \"0\"}}\n", "{w: |\"0\"}", "data.exact.w",
       {"'w' is no output (outputs: u"}},
      {"PdeDataGridSizes", pde(base) + "data: {exact: {u: \"0\", grid: [5]}}\n", "grid: |[5]", "data.exact.grid",
       {"expected 2 sizes (one per input"}},
      {"PdeDataTwoNoises", pde(base) + "data: {exact: {u: \"0\", noise: 0.1, noise_std: 0.1}}\n", "noise_std: |0.1",
       "data.exact.noise_std", {"give noise or noise_std, not both"}},
      // problem: pde, unknown fields.
      {"PdeUnknownFieldInputsWithoutHidden", pde(base) + "unknown_fields:\n  a: {inputs: [x]}\n", "inputs: |[x]",
       "unknown_fields.a.inputs", {"needs a network of its own"}},
      {"PdeUnknownFieldTruthWithoutReference", pde(base) + "unknown_fields:\n  a: {true: \"x\"}\n", "true: |\"x\"",
       "unknown_fields.a.true", {"a truth needs reference.exact"}},
      // YAML itself.
      {"YamlSyntax", edit("lower: [0, 0]", "lower: [0, 0"), "  upper|: [1, 1]", "",
       {"YAML syntax error"}},
      {"DuplicateKey", edit("  seed: 0\n", "  seed: 0\n  seed: 1\n"), "  |seed: 1", "training",
       {"duplicate key 'seed' (first on line 16)"}},
      {"TopLevelList", "- poisson\n- wave\n", "|- poisson", "",
       {"expected a mapping of keys at the top level, got a list of 2"}},
      // --set: values set there carry no line; a bad path names the assignment.
      {"SetStringForNumber", base, "", "training.stages[0].lr", {"expected a number, got 'abc'"},
       {"--set", "training.stages[0].lr=abc"}},
      {"SetIndexOutOfRange", base, "", "training.stages",
       {"index 3 out of range (the list has 1 items)"}, {"--set", "training.stages[3].lr=1"},
       "--set 'training.stages[3].lr=1'"},
      {"SetUnknownKey", base, "", "training.sead", {"unknown key 'sead'", "seed"},
       {"--set", "training.sead=3"}},
  };
}

class BadConfigTest : public ::testing::TestWithParam<BadConfig> {
 protected:
  void SetUp() override {
    const auto dir = scratch_dir();
    work_ = dir / "work";
    capture_ = dir / "capture";
    std::filesystem::create_directories(work_);
    config_ = work_ / "bad.yaml";
    write_text(config_, GetParam().yaml);
  }

  // The one line stderr should hold.
  void expect_error_line(const Outcome& o) const {
    const BadConfig& c = GetParam();
    EXPECT_EQ(o.code, 2) << describe(o);
    ASSERT_FALSE(o.err.empty()) << describe(o);
    EXPECT_EQ(o.err.back(), '\n') << describe(o);
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << "not one line:\n" << o.err;
    std::string prefix = "nfield: error: " + (c.file.empty() ? config_.string() : c.file);
    if (!c.at.empty()) prefix += ":" + location(c);
    prefix += ": ";
    if (!c.key_path.empty()) prefix += c.key_path + ": ";
    EXPECT_EQ(o.err.substr(0, prefix.size()), prefix) << "stderr: " << o.err;
    for (const std::string& part : c.expected)
      EXPECT_NE(o.err.find(part), std::string::npos) << "stderr lacks '" << part << "':\n" << o.err;
  }

  std::vector<std::string> arguments(const std::string& command) const {
    std::vector<std::string> args{command, config_.string()};
    args.insert(args.end(), GetParam().args.begin(), GetParam().args.end());
    return args;
  }

  std::filesystem::path work_, capture_, config_;
};

TEST_P(BadConfigTest, ValidateRefusesWithLocatedMessage) {
  const Outcome o = run_nfield(arguments("validate"), work_, capture_);
  expect_error_line(o);
  EXPECT_EQ(o.out, "");
  EXPECT_EQ(tree(work_), std::vector<std::string>{"bad.yaml"});
}

TEST_P(BadConfigTest, RunRefusesAndWritesNothing) {
  std::vector<std::string> args = arguments("run");
  const std::filesystem::path out = work_ / "out_dir";
  args.insert(args.end(), {"--out", out.string()});
  const Outcome o = run_nfield(args, work_, capture_);
  expect_error_line(o);
  EXPECT_EQ(o.out, "");
  EXPECT_FALSE(std::filesystem::exists(out));
  EXPECT_EQ(tree(work_), std::vector<std::string>{"bad.yaml"});
}

INSTANTIATE_TEST_SUITE_P(Cases, BadConfigTest, ::testing::ValuesIn(bad_configs()),
                         [](const ::testing::TestParamInfo<BadConfig>& info) { return info.param.name; });

// A config named without a folder, from its own folder: its data folder is ".", and the run
// writes its outputs (an empty parent path once made `std::filesystem::absolute` throw).
TEST(GoodConfig, RunsWhenNamedWithoutAFolder) {
  const auto dir = scratch_dir();
  const auto work = dir / "work";
  std::filesystem::create_directories(work);
  write_text(work / "good.yaml", kBase);
  const Outcome o = run_nfield({"run", "good.yaml", "--out", "out"}, work, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  EXPECT_TRUE(std::filesystem::exists(work / "out" / "metrics.json")) << describe(o);
  EXPECT_TRUE(std::filesystem::exists(work / "out" / "checkpoint.h5")) << describe(o);
}

// The base config itself is fine (so each case above fails for its own reason only).
TEST(GoodConfig, ValidatesAndRuns) {
  const auto dir = scratch_dir();
  const auto work = dir / "work";
  std::filesystem::create_directories(work);
  write_text(work / "good.yaml", kBase);
  Outcome o = run_nfield({"validate", (work / "good.yaml").string()}, work, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("good.yaml: valid"), std::string::npos) << o.out;
  EXPECT_EQ(o.err, "");
  EXPECT_EQ(tree(work), std::vector<std::string>{"good.yaml"});

  o = run_nfield({"run", (work / "good.yaml").string(), "--out", (work / "out").string()}, work,
                 dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  for (const char* file : {"config.yaml", "checkpoint.h5", "solution.vti", "metrics.json"})
    EXPECT_TRUE(std::filesystem::exists(work / "out" / file)) << file;
}

// Command lines that CLI11 refuses: exit code 2, the reason on stderr, nothing written.
struct BadCommand {
  std::string name;
  // "GOOD" stands for a valid config, "CKPT" for an HDF5 file with a group 'field', "H5" for
  // one without, "OUT" for an output folder.
  std::vector<std::string> args;
  std::vector<std::string> expected;
};

void PrintTo(const BadCommand& c, std::ostream* out) { *out << c.name; }

class BadCommandTest : public ::testing::TestWithParam<BadCommand> {};

TEST_P(BadCommandTest, ExitsWithTwoAndWritesNothing) {
  const auto dir = scratch_dir();
  const auto work = dir / "work";
  std::filesystem::create_directories(work);
  write_text(work / "good.yaml", kBase);
  {
    io::H5Writer checkpoint(work / "ckpt.h5");
    checkpoint.create_group("field");
    checkpoint.commit();
    io::H5Writer other(work / "other.h5");
    other.create_group("images");
    other.commit();
  }
  const std::map<std::string, std::string> names{{"GOOD", "good.yaml"}, {"CKPT", "ckpt.h5"},
                                                 {"H5", "other.h5"}, {"OUT", "out"}};
  std::vector<std::string> args;
  for (const std::string& a : GetParam().args)
    args.push_back(names.count(a) ? (work / names.at(a)).string() : a);
  const Outcome o = run_nfield(args, work, dir / "capture");
  EXPECT_EQ(o.code, 2) << describe(o);
  for (const std::string& part : GetParam().expected)
    EXPECT_NE(o.err.find(part), std::string::npos) << "stderr lacks '" << part << "':\n" << o.err;
  EXPECT_EQ(tree(work), (std::vector<std::string>{"ckpt.h5", "good.yaml", "other.h5"}));
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadCommandTest,
    ::testing::ValuesIn(std::vector<BadCommand>{
        {"RunMissingConfig", {"run", "missing.yaml", "--out", "OUT"}, {"missing.yaml", "does not exist"}},
        {"ValidateMissingConfig", {"validate", "missing.yaml"}, {"missing.yaml", "does not exist"}},
        {"RunConfigIsFolder", {"run", ".", "--out", "OUT"}, {"."}},
        {"ResumeMissingCheckpoint", {"run", "GOOD", "--resume", "missing.h5", "--out", "OUT"},
         {"missing.h5", "does not exist"}},
        {"EvalMissingCheckpoint", {"eval", "missing.h5", "--out", "OUT"}, {"missing.h5", "does not exist"}},
        {"EvalNotACheckpoint", {"eval", "GOOD", "--out", "OUT"}, {"good.yaml", "not an HDF5 file"}},
        {"EvalHdf5WithoutField", {"eval", "H5", "--out", "OUT"}, {"other.h5", "not an nfield checkpoint"}},
        {"ResumeNotACheckpoint", {"run", "GOOD", "--resume", "GOOD", "--out", "OUT"},
         {"good.yaml", "not an HDF5 file"}},
        {"EvalGridTooSmall", {"eval", "CKPT", "--grid", "1", "--out", "OUT"}, {"--grid", "not in range 2 to 4096"}},
        {"EvalGridNotANumber", {"eval", "CKPT", "--grid", "many", "--out", "OUT"}, {"--grid"}},
        {"RunWithoutConfig", {"run"}, {"config"}},
        {"UnknownOption", {"run", "GOOD", "--bogus", "--out", "OUT"}, {"--bogus"}},
        {"UnknownCommand", {"frobnicate"}, {"subcommand"}},
        {"NoCommand", {}, {"subcommand"}},
        {"SetWithoutEquals", {"run", "GOOD", "--set", "training.seed", "--out", "OUT"},
         {"--set 'training.seed'", "expected KEY.PATH=VALUE"}},
    }),
    [](const ::testing::TestParamInfo<BadCommand>& info) { return info.param.name; });

TEST(Help, MainHelpListsCommands) {
  const auto dir = scratch_dir();
  const Outcome o = run_nfield({"--help"}, dir, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  for (const char* part : {"run", "validate", "eval", "bench", "--version"})
    EXPECT_NE(o.out.find(part), std::string::npos) << "help lacks '" << part << "':\n" << o.out;
}

TEST(Help, RunHelpListsOptions) {
  const auto dir = scratch_dir();
  const Outcome o = run_nfield({"run", "--help"}, dir, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  for (const char* part : {"config", "--set", "--out", "--resume", "YAML"})
    EXPECT_NE(o.out.find(part), std::string::npos) << "help lacks '" << part << "':\n" << o.out;
  EXPECT_EQ(tree(dir), (std::vector<std::string>{"capture", "capture/stderr.txt"}));
}

TEST(Help, ValidateAndEvalHelp) {
  const auto dir = scratch_dir();
  Outcome o = run_nfield({"validate", "--help"}, dir, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  EXPECT_NE(o.out.find("--set"), std::string::npos) << o.out;
  o = run_nfield({"eval", "--help"}, dir, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  for (const char* part : {"checkpoint", "--grid", "--out"})
    EXPECT_NE(o.out.find(part), std::string::npos) << "help lacks '" << part << "':\n" << o.out;
}

TEST(Help, Version) {
  const auto dir = scratch_dir();
  const Outcome o = run_nfield({"--version"}, dir, dir / "capture");
  EXPECT_EQ(o.code, 0) << describe(o);
  EXPECT_FALSE(o.out.empty());
}

}  // namespace
}  // namespace nfield::apps::testing
