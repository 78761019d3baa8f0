// SPDX-License-Identifier: MIT
#include "io/config.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>

#include <gtest/gtest.h>

namespace nfield::io {
namespace {

// Line numbers matter: the error cases below point into this text.
constexpr const char* kConfig =
    "problem: poisson\n"                                   // 1
    "domain:\n"                                            // 2
    "  lower: [0, 0]\n"                                    // 3
    "  upper: [1, abc]\n"                                  // 4
    "training:\n"                                          // 5
    "  seed: 1.5\n"                                        // 6
    "  stages:\n"                                          // 7
    "    - {optimizer: adam, steps: 3000, lr: 1.0e-4}\n"   // 8
    "    - optimizer: lbfgs\n"                             // 9
    "      lrr: 0.5\n"                                     // 10
    "output:\n"                                            // 11
    "  every: -3\n"                                        // 12
    "  dir: out\n"                                         // 13
    "  big: 1e12\n"                                        // 14
    "  flag: maybe\n"                                      // 15
    "equation:\n"                                          // 16
    "  source: sin(pi*q)\n"                                // 17
    "  quoted: \"2*x + $\"\n";                             // 18

ConfigNode config() { return parse_config(kConfig, "cfg.yaml"); }

std::filesystem::path scratch(const std::string& name) {
  const auto dir = std::filesystem::path(NFIELD_BINARY_DIR) / "test_scratch" / "io_config" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

struct ErrorCase {
  std::string name;
  std::function<void()> action;
  std::string expected;  // the whole what()
};

void PrintTo(const ErrorCase& c, std::ostream* out) { *out << c.name; }

class ConfigErrorTest : public ::testing::TestWithParam<ErrorCase> {};

TEST_P(ConfigErrorTest, MessageIsLocated) {
  const ErrorCase& c = GetParam();
  try {
    c.action();
    FAIL() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), c.expected);
  }
}

const std::vector<ErrorCase> kErrorCases = {
    {"WrongTypeInList", [] { config().child("domain").get<std::vector<double>>("upper"); },
     "cfg.yaml:4:14: domain.upper[1]: expected a number, got 'abc'"},
    {"WrongTypeInteger", [] { config().child("training").get<int>("seed"); },
     "cfg.yaml:6:9: training.seed: expected an integer, got '1.5'"},
    {"MissingRequiredKey",
     [] { config().child("training").child("stages").at(1).get<double>("lr"); },
     "cfg.yaml:9:7: training.stages[1].lr: missing required key 'lr'"},
    {"UnknownKey",
     [] {
       ConfigNode stage = config().child("training").child("stages").at(1);
       stage.get<std::string>("optimizer");
       stage.get_or("lr", 1e-3);
       stage.reject_unknown_keys();
     },
     "cfg.yaml:10:7: training.stages[1].lrr: unknown key 'lrr' (valid keys: optimizer, lr)"},
    {"UnknownKeyRecursive",
     [] {
       ConfigNode root = config();
       for (const char* key : {"problem", "domain", "training", "output", "equation"})
         root.has(key);
       root.child("training").has("seed");
       ConfigNode stages = root.child("training").child("stages");
       for (std::size_t i = 0; i < stages.size(); ++i) {
         stages.at(i).get<std::string>("optimizer");
         stages.at(i).get_or("steps", 100);
         stages.at(i).get_or("lr", 1e-3);
       }
       root.reject_unknown_keys_recursive();
     },
     "cfg.yaml:10:7: training.stages[1].lrr: unknown key 'lrr' (valid keys: optimizer, steps, lr)"},
    {"ExpectKeys", [] { config().child("output").expect_keys({"every", "big", "flag"}); },
     "cfg.yaml:13:3: output.dir: unknown key 'dir' (valid keys: every, big, flag)"},
    {"BadListLength", [] { config().child("domain").get_list<double>("lower", 3); },
     "cfg.yaml:3:10: domain.lower: expected a list of 3 numbers, got a list of 2"},
    {"ScalarForList", [] { config().get_list<double>("problem", 2); },
     "cfg.yaml:1:10: problem: expected a list of 2 numbers, got 'poisson'"},
    {"BadChoice",
     [] {
       config().child("training").child("stages").at(0).get_choice("optimizer",
                                                                   {"sgd", "lbfgs"});
     },
     "cfg.yaml:8:19: training.stages[0].optimizer: expected one of sgd, lbfgs; got 'adam'"},
    {"NotPositive", [] { config().child("output").get_positive<int>("every"); },
     "cfg.yaml:12:10: output.every: expected a positive integer, got '-3'"},
    {"OutOfRange", [] { config().child("output").get_in_range<double>("every", 0.0, 1.0); },
     "cfg.yaml:12:10: output.every: expected a number in [0, 1], got '-3'"},
    {"IntOverflow", [] { config().child("output").get<int>("big"); },
     "cfg.yaml:14:8: output.big: expected an integer between -2147483648 and 2147483647, "
     "got '1e12'"},
    {"NotABool", [] { config().child("output").get<bool>("flag"); },
     "cfg.yaml:15:9: output.flag: expected true or false, got 'maybe'"},
    {"ChildOfScalar", [] { config().child("problem"); },
     "cfg.yaml:1:10: problem: expected a mapping or a list, got 'poisson'"},
    {"StringFromMapping", [] { config().get<std::string>("domain"); },
     "cfg.yaml:3:3: domain: expected a string, got a mapping"},
    {"IndexOutOfRange", [] { config().child("training").child("stages").at(5); },
     "cfg.yaml:8:5: training.stages: index 5 out of range (the list has 2 items)"},
    {"Require", [] { config().child("domain").require(false, "expected lower < upper"); },
     "cfg.yaml:3:3: domain: expected lower < upper"},
    {"RequireKey",
     [] { config().child("domain").require("upper", false, "expected upper > lower"); },
     "cfg.yaml:4:10: domain.upper: expected upper > lower"},
    {"ExpressionUnknownName", [] { config().child("equation").get_expression("source"); },
     "cfg.yaml:17:18: equation.source: in expression 'sin(pi*q)': Unexpected token \"q\" "
     "found at position 7."},
    {"ExpressionQuoted", [] { config().child("equation").get_expression("quoted"); },
     "cfg.yaml:18:18: equation.quoted: in expression '2*x + $': Unexpected token \"$ \" "
     "found at position 6."},
    {"YamlSyntax", [] { parse_config("a: [1, 2\nb: 3\n", "bad.yaml"); },
     "bad.yaml:2:2: YAML syntax error: end of sequence flow not found"},
    {"YamlBadIndent", [] { parse_config("a: 1\n b: 2\n", "bad.yaml"); },
     "bad.yaml:2:3: YAML syntax error: illegal map value"},
    {"DuplicateKey", [] { parse_config("a: 1\nb:\n  c: 2\n  c: 3\n", "dup.yaml"); },
     "dup.yaml:4:3: b: duplicate key 'c' (first on line 3)"},
    {"TopLevelList", [] { parse_config("- 1\n- 2\n", "list.yaml"); },
     "list.yaml:1:1: expected a mapping of keys at the top level, got a list of 2"},
    {"MissingFile", [] { load_config("no/such/config.yaml"); },
     "no/such/config.yaml: config file not found"},
    {"SetWithoutEquals",
     [] {
       YAML::Node root;
       apply_override(root, "training.lr");
     },
     "--set 'training.lr': expected KEY.PATH=VALUE"},
    {"SetEmptyName", [] { parse_config(kConfig, "cfg.yaml", std::vector<std::string>{"training..lr=1"}); },
     "--set 'training..lr=1': expected a key name at position 10 of 'training..lr'"},
    {"SetBadIndex",
     [] {
       parse_config(kConfig, "cfg.yaml", std::vector<std::string>{"training.stages[x].lr=1"});
     },
     "--set 'training.stages[x].lr=1': expected [INDEX] at position 16 of "
     "'training.stages[x].lr'"},
    {"SetIndexOutOfRange",
     [] {
       parse_config(kConfig, "cfg.yaml", std::vector<std::string>{"training.stages.5.lr=1"});
     },
     "--set 'training.stages.5.lr=1': training.stages: index 5 out of range (the list has 2 "
     "items)"},
    {"SetIntoScalar",
     [] { parse_config(kConfig, "cfg.yaml", std::vector<std::string>{"problem.kind=1"}); },
     "--set 'problem.kind=1': problem: expected a mapping to set key 'kind' in, got 'poisson'"},
    {"SetBadValue",
     [] { parse_config(kConfig, "cfg.yaml", std::vector<std::string>{"domain.lower=[1, 2"}); },
     "--set 'domain.lower=[1, 2': cannot parse the value as YAML: end of sequence flow not "
     "found"},
    {"SetMissingValue",
     [] { parse_config(kConfig, "cfg.yaml", std::vector<std::string>{"domain.lower= "}); },
     "--set 'domain.lower= ': missing value after '='"},
    {"OverriddenValueHasNoLine",
     [] {
       parse_config(kConfig, "cfg.yaml", std::vector<std::string>{"training.seed=abc"})
           .child("training")
           .get<int>("seed");
     },
     "cfg.yaml: training.seed: expected an integer, got 'abc'"},
};

INSTANTIATE_TEST_SUITE_P(Cases, ConfigErrorTest, ::testing::ValuesIn(kErrorCases),
                         [](const auto& info) { return info.param.name; });

TEST(ConfigError, Parts) {
  try {
    config().child("training").get<int>("seed");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "cfg.yaml");
    EXPECT_EQ(e.line(), 6);
    EXPECT_EQ(e.column(), 9);
    EXPECT_EQ(e.key_path(), "training.seed");
    EXPECT_EQ(e.message(), "expected an integer, got '1.5'");
  }
}

TEST(ConfigNode, ReadsTypedValues) {
  ConfigNode root = parse_config(
      "b1: true\nb2: No\nb3: ON\n"
      "i1: 42\ni2: -7\ni3: 1e4\ni4: +5\n"
      "big: 9007199254740993\n"
      "d1: 1.0e-4\nd2: 3\nd3: .inf\nd4: -.Inf\nd5: .nan\nd6: \"2.5\"\n"
      "s: hello world\nempty_string: ''\n"
      "vd: [0, 1.5, -2e3]\nvi: [1, 2, 3]\nvs: [a, 'b c']\nnothing:\nnull_value: ~\n",
      "t.yaml");
  EXPECT_TRUE(root.get<bool>("b1"));
  EXPECT_FALSE(root.get<bool>("b2"));
  EXPECT_TRUE(root.get<bool>("b3"));
  EXPECT_EQ(root.get<int>("i1"), 42);
  EXPECT_EQ(root.get<int>("i2"), -7);
  EXPECT_EQ(root.get<int>("i3"), 10000);
  EXPECT_EQ(root.get<int>("i4"), 5);
  EXPECT_EQ(root.get<std::int64_t>("big"), 9007199254740993LL);
  EXPECT_EQ(root.get<double>("d1"), 1.0e-4);
  EXPECT_EQ(root.get<double>("d2"), 3.0);
  EXPECT_EQ(root.get<double>("d3"), std::numeric_limits<double>::infinity());
  EXPECT_EQ(root.get<double>("d4"), -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(root.get<double>("d5")));
  EXPECT_EQ(root.get<double>("d6"), 2.5);
  EXPECT_EQ(root.get<std::string>("s"), "hello world");
  EXPECT_EQ(root.get<std::string>("empty_string"), "");
  EXPECT_EQ(root.get<std::string>("i1"), "42");
  EXPECT_EQ(root.get<std::vector<double>>("vd"), (std::vector<double>{0, 1.5, -2000}));
  EXPECT_EQ(root.get<std::vector<int>>("vi"), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(root.get<std::vector<std::int64_t>>("vi"), (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(root.get<std::vector<std::string>>("vs"), (std::vector<std::string>{"a", "b c"}));
  EXPECT_EQ(root.get_list<int>("vi", 3), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(root.child("vi").at(1).as<int>(), 2);
  // Empty values count as absent for get_or, and are an error for get.
  EXPECT_EQ(root.get_or("nothing", 5), 5);
  EXPECT_EQ(root.get_or("null_value", 2.5), 2.5);
  EXPECT_EQ(root.get_or("absent", std::string("x")), "x");
  EXPECT_EQ(root.get_or("absent", "y"), "y");
  EXPECT_EQ(root.get_or("i1", 0), 42);
  EXPECT_EQ(root.get_or<std::vector<double>>("absent", {1, 2}), (std::vector<double>{1, 2}));
  EXPECT_THROW(root.get<int>("nothing"), ConfigError);
  EXPECT_TRUE(root.has("nothing"));
  EXPECT_FALSE(root.has("absent"));
}

TEST(ConfigNode, RangesAndChoices) {
  ConfigNode root = parse_config("lr: 1e-3\nsteps: 10\nzero: 0\nopt: LBFGS\n", "t.yaml");
  EXPECT_EQ(root.get_positive<double>("lr"), 1e-3);
  EXPECT_EQ(root.get_positive<int>("steps"), 10);
  EXPECT_EQ(root.get_nonnegative<int>("zero"), 0);
  EXPECT_THROW(root.get_positive<int>("zero"), ConfigError);
  EXPECT_EQ(root.get_in_range<std::int64_t>("steps", 1, 10), 10);
  EXPECT_THROW(root.get_in_range<int>("steps", 1, 9), ConfigError);
  EXPECT_EQ(root.get_choice("opt", {"adam", "lbfgs"}), "lbfgs");
  EXPECT_EQ(root.get_choice("missing", {"adam", "lbfgs"}, "adam"), "adam");
  EXPECT_EQ(root.get_choice("opt", {"adam", "lbfgs"}, "adam"), "lbfgs");
}

TEST(ConfigNode, StructureQueries) {
  ConfigNode root = config();
  EXPECT_TRUE(root.is_map());
  EXPECT_EQ(root.keys(), (std::vector<std::string>{"problem", "domain", "training", "output",
                                                   "equation"}));
  EXPECT_EQ(root.size(), 5u);
  ConfigNode stages = root.child("training").child("stages");
  EXPECT_TRUE(stages.is_sequence());
  EXPECT_EQ(stages.size(), 2u);
  EXPECT_EQ(stages.path(), "training.stages");
  EXPECT_EQ(stages.at(0).path(), "training.stages[0]");
  EXPECT_TRUE(stages.at(0).child_or_empty("x").is_map());
  EXPECT_TRUE(root.child("domain").is_map());
  EXPECT_TRUE(root.child("domain").child("lower").at(0).is_scalar());
  EXPECT_EQ(stages.at(0).get<double>("lr"), 1.0e-4);
  EXPECT_EQ(stages.at(0).get<int>("steps"), 3000);
  // A section that is absent reads as empty, and its defaults apply.
  ConfigNode missing = root.child_or_empty("logging");
  EXPECT_EQ(missing.size(), 0u);
  EXPECT_EQ(missing.get_or("level", 2), 2);
  EXPECT_EQ(missing.path(), "logging");
}

TEST(ConfigNode, KeyTrackingIsSharedBetweenCopiesAndChildren) {
  ConfigNode root = parse_config(
      "a: 1\nsection:\n  x: 1\n  y: 2\nlist:\n  - {k: 1}\n  - {k: 2}\nraw: {anything: 1}\n"
      "ignored: {z: 1}\n",
      "t.yaml");
  root.get<int>("a");
  root.child("section").get<int>("x");
  ConfigNode copy = root;
  copy.child("section").get<int>("y");  // a different ConfigNode for the same section
  for (std::size_t i = 0; i < root.child("list").size(); ++i) root.child("list").at(i).get<int>("k");
  root.child("raw").accept_all_keys();
  EXPECT_THROW(root.reject_unknown_keys(), ConfigError);  // 'ignored' never asked for
  root.has("ignored");  // known now; its section was never opened, so not checked inside
  EXPECT_NO_THROW(root.reject_unknown_keys());
  EXPECT_NO_THROW(root.child("section").reject_unknown_keys());
  EXPECT_NO_THROW(root.reject_unknown_keys_recursive());
}

TEST(ConfigNode, RecursiveCheckFindsNestedUnknownKey) {
  ConfigNode root = parse_config("field:\n  type: siren\n  hiden: [64, 64]\n", "t.yaml");
  ConfigNode field = root.child("field");
  field.get<std::string>("type");
  field.get_or<std::vector<int>>("hidden", {256, 256});
  EXPECT_NO_THROW(root.reject_unknown_keys());
  try {
    root.reject_unknown_keys_recursive();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "t.yaml:3:3: field.hiden: unknown key 'hiden' (valid keys: type, hidden)");
  }
}

// What `f` throws as a ConfigError, or "" if nothing.
template <class F>
std::string config_error(F f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ConfigNode, KeysMissingFromAFileWithoutKeysPointAtItsStart) {
  for (const char* text : {"", "# only a comment\n"})
    EXPECT_EQ(config_error([&] { parse_config(text, "e.yaml").get<std::string>("problem"); }),
              "e.yaml:1:1: problem: missing required key 'problem'")
        << text;
}

TEST(ConfigNode, KeysOfAnAbsentSectionPointAtItsParent) {
  const ConfigNode root = parse_config("problem: poisson\nfield: {type: siren}\n", "a.yaml");
  EXPECT_EQ(config_error([&] { root.child_or_empty("training").get<int>("steps"); }),
            "a.yaml:1:1: training.steps: missing required key 'steps'");
  EXPECT_EQ(config_error([&] { root.child("field").child_or_empty("encoding").get<int>("n"); }),
            "a.yaml:2:8: field.encoding.n: missing required key 'n'");
}

TEST(ConfigNode, HasListAndHasMapTellTheKindOfAValue) {
  const ConfigNode root =
      parse_config("item: {on: [x_min], value: \"0\", balance: {method: fixed}}\n", "h.yaml");
  const ConfigNode item = root.child("item");
  EXPECT_TRUE(item.has_list("on"));
  EXPECT_FALSE(item.has_list("value"));
  EXPECT_FALSE(item.has_list("absent"));  // no exception for a key that is not there
  EXPECT_TRUE(item.has_map("balance"));
  EXPECT_FALSE(item.has_map("on"));
  item.get<std::string>("value");
  item.child("balance").get<std::string>("method");
  EXPECT_NO_THROW(root.reject_unknown_keys_recursive());  // has_* count as asking for the key
  // On a value that is no mapping, the question is a located error, not a yaml-cpp one.
  EXPECT_EQ(config_error([&] { root.child("item").child("on").has_list("x"); }),
            "h.yaml:1:12: item.on: expected a mapping with key 'x', got a list of 1");
}

TEST(ConfigNode, ExpressionsFromConfig) {
  ConfigNode root = parse_config("source: 2*x + y\nexact: 'x*t'\n", "t.yaml");
  Expression source = root.get_expression("source", {"x", "y"});
  EXPECT_DOUBLE_EQ(source.evaluate(std::vector<double>{1.0, 3.0}), 5.0);
  EXPECT_TRUE(root.get_expression("exact").uses("t"));
  EXPECT_EQ(root.get_expression_or("missing", "0").text(), "0");
}

TEST(ApplyOverride, SetsCreatesAndIndexes) {
  YAML::Node root = YAML::Load(
      "training:\n  stages:\n    - {lr: 1}\n    - {lr: 2}\ndomain:\n  lower: [0, 0]\nempty:\n");
  apply_override(root, "training.stages[1].lr=1e-3");
  apply_override(root, "training.stages.0.lr = 5");
  apply_override(root, "domain.lower=[-1, -2]");
  apply_override(root, "output.dir=out/run 1");
  apply_override(root, "empty.child=true");
  apply_override(root, "field={type: siren, w0: 30}");
  apply_override(root, "domain.lower[1]=7");
  ConfigNode config(root, "t.yaml");
  EXPECT_EQ(config.child("training").child("stages").at(1).get<double>("lr"), 1e-3);
  EXPECT_EQ(config.child("training").child("stages").at(0).get<int>("lr"), 5);
  EXPECT_EQ(config.child("domain").get<std::vector<double>>("lower"), (std::vector<double>{-1, 7}));
  EXPECT_EQ(config.child("output").get<std::string>("dir"), "out/run 1");
  EXPECT_TRUE(config.child("empty").get<bool>("child"));
  EXPECT_EQ(config.child("field").get<double>("w0"), 30);

  YAML::Node fresh;
  apply_override(fresh, "a.b.c=1");
  EXPECT_EQ(fresh["a"]["b"]["c"].as<int>(), 1);
}

TEST(LoadConfig, ReadsFileWithOverrides) {
  const auto dir = scratch("ReadsFileWithOverrides");
  std::ofstream(dir / "run.yaml") << "training:\n  seed: 0\n  lr: 1e-4\n";
  const std::vector<std::string> overrides = {"training.seed=3", "training.extra=[1, 2]"};
  ConfigNode root = load_config(dir / "run.yaml", overrides);
  EXPECT_EQ(root.file(), (dir / "run.yaml").string());
  EXPECT_EQ(root.child("training").get<int>("seed"), 3);
  EXPECT_EQ(root.child("training").get<std::vector<int>>("extra"), (std::vector<int>{1, 2}));
  std::ofstream(dir / "empty.yaml") << "# nothing\n";
  EXPECT_EQ(load_config(dir / "empty.yaml").size(), 0u);
  std::filesystem::remove_all(dir);
}

TEST(ToYaml, DeterministicAndRoundTrips) {
  ConfigNode root = config();
  const std::string once = to_yaml(root.yaml());
  const std::string twice = to_yaml(parse_config(once, "again.yaml").yaml());
  EXPECT_EQ(once, twice);
  ConfigNode again = parse_config(once, "again.yaml");
  EXPECT_EQ(again.child("training").child("stages").at(0).get<double>("lr"), 1.0e-4);
  EXPECT_EQ(again.child("equation").get<std::string>("quoted"), "2*x + $");
  EXPECT_NE(once.find("lower: [0, 0]"), std::string::npos) << once;

  // A part of the program writing back its section with defaults filled in.
  YAML::Node resolved;
  resolved["problem"] = "poisson";
  YAML::Node training;
  training["seed"] = 0;
  training["lr"] = yaml_number(0.1);
  training["tiny"] = yaml_number(1e-5);
  training["w0"] = yaml_number(30.0);
  training["hidden"] = std::vector<int>{256, 256};
  training["lower"] = yaml_numbers(std::vector<double>{0.1, -0.25});
  training["name"] = std::string("null");
  training["blank"] = std::string("");
  resolved["training"] = training;
  const std::string text = to_yaml(resolved);
  EXPECT_EQ(text,
            "problem: poisson\n"
            "training:\n"
            "  seed: 0\n"
            "  lr: 0.1\n"
            "  tiny: 1.0e-05\n"
            "  w0: 30\n"
            "  hidden: [256, 256]\n"
            "  lower: [0.1, -0.25]\n"
            "  name: \"null\"\n"
            "  blank: \"\"\n");
  ConfigNode back = parse_config(text, "resolved.yaml");
  EXPECT_EQ(back.child("training").get<double>("lr"), 0.1);
  EXPECT_EQ(back.child("training").get<double>("tiny"), 1e-5);
  EXPECT_EQ(back.child("training").get<std::string>("name"), "null");
  EXPECT_EQ(back.child("training").get<std::string>("blank"), "");
  EXPECT_EQ(yaml_number(std::numeric_limits<double>::infinity()).Scalar(), ".inf");
  EXPECT_EQ(yaml_number(-0.0).Scalar(), "-0");
  // The shortest text still reads back to the same bits.
  for (double value : {0.1, 1.0 / 3.0, 2.2250738585072014e-308, 1e300, 123456789.125})
    EXPECT_EQ(parse_config("v: " + yaml_number(value).Scalar(), "v.yaml").get<double>("v"), value);
}

}  // namespace
}  // namespace nfield::io
