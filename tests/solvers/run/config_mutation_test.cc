// SPDX-License-Identifier: MIT
//
// Every shipped config, mutated the way a user's typos would: each value replaced by a
// word, a mapping, an empty string, a broken expression, NaN, a negative, zero, a
// fraction or a huge number; each key renamed, dropped or joined by an unknown one; the
// file cut after every line and in the middle of every line. Each mutant is validated
// in-process (solvers::load_run, what `nfield validate` runs; it never trains) and must
//  * be rejected when the mutation is known to break it (a word where a number goes, a
//    negative step count, an unknown key, ...), and
//  * when rejected, be rejected by an io::ConfigError whose message starts with
//    `FILE:LINE:COL: KEY.PATH: ` (a YAML syntax error or a top level that is no mapping
//    has no key path, only `FILE:LINE:COL: `).
// Mutants whose validity depends on the key (a zero, a dropped key, a cut file) may pass.
//
// Configs whose validation reads or computes much (posed images, a mesh, a finite-difference
// reference) test a fixed sample of their mutants (kSampleStride); NFIELD_ALL_MUTANTS=1
// tests them all.
//
// Mutants are written into a scratch folder; data paths still resolve against configs/ (the
// data_dir argument of load_run), so a mutant reads the same data files as its original.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "io/config.h"
#include "io/text.h"
#include "solvers/run/run.h"
#include "tests/testing/scratch.h"

namespace nfield::solvers {
namespace {

const std::filesystem::path kConfigs = std::filesystem::path(NFIELD_SOURCE_DIR) / "configs";

// A step of a key path in the YAML tree: a key of a mapping or an index of a list.
using Step = std::variant<std::string, std::size_t>;
using Path = std::vector<Step>;

std::string path_text(const Path& path) {
  std::string out;
  for (const Step& step : path) {
    if (const auto* key = std::get_if<std::string>(&step))
      out += (out.empty() ? "" : ".") + *key;
    else
      out += "[" + std::to_string(std::get<std::size_t>(step)) + "]";
  }
  return out;
}

std::string last_key(const Path& path) {
  for (auto it = path.rbegin(); it != path.rend(); ++it)
    if (const auto* key = std::get_if<std::string>(&*it)) return *key;
  return "";
}

// Keys whose numbers must be positive (a count, a size, a rate, a speed, a loss weight):
// -3 there must be rejected.
const std::set<std::string> kPositive = {
    "steps", "lr", "lr_final", "hidden", "color_hidden", "grid", "interior", "boundary",
    "initial", "rays", "points", "surface", "interface", "intervals", "samples", "resolution",
    "seconds", "every", "log_every", "threads", "levels", "features_per_level",
    "base_resolution", "finest_resolution", "sections", "samples_per_section",
    "steps_per_diagonal", "resample_every", "frames", "speed", "speeds", "memory", "crop",
    "weight", "sdf_weight", "normal_weight", "eikonal_weight", "off_surface_weight",
    "interface_weight", "frequencies", "direction_frequencies", "audio_seconds"};
// Keys whose numbers are counts: 1.5 there must be rejected.
const std::set<std::string> kInteger = {
    "steps", "hidden", "color_hidden", "grid", "interior", "boundary", "initial", "rays",
    "points", "surface", "interface", "intervals", "samples", "resolution", "every",
    "log_every", "threads", "levels", "features_per_level", "base_resolution",
    "finest_resolution", "sections", "samples_per_section", "steps_per_diagonal",
    "resample_every", "frames", "memory", "crop", "frequencies", "direction_frequencies",
    "seed", "from_stage"};
// `initial` counts the points of a batch (training.batch.initial); elsewhere it is a value
// of any sign (constants.NAME.initial, an unknown constant's start).
bool in_key_set(const std::set<std::string>& keys, const Path& path) {
  const std::string key = last_key(path);
  if (key == "initial") {
    const Path parent(path.begin(), path.end() - 1);
    return last_key(parent) == "batch";
  }
  return keys.count(key) > 0;
}
// Free text, where any string is a valid value.
const std::set<std::string> kFreeText = {"dir"};
// Mappings whose keys are the user's own names, read by nothing else (a functional's name).
const std::set<std::string> kFreeNames = {"functionals"};

bool is_number(const std::string& text) {
  try {
    std::size_t used = 0;
    std::stod(text, &used);
    return used == text.size();
  } catch (const std::exception&) {
    return false;
  }
}

bool is_bool(std::string_view raw) {
  const std::string text = io::to_lower(raw);
  return text == "true" || text == "false" || text == "yes" || text == "no" || text == "on" ||
         text == "off";
}

struct Mutant {
  std::string name;  // what was changed, for failure messages
  std::string text;
  bool must_reject;
};

YAML::Node at_path(YAML::Node root, const Path& path) {
  YAML::Node node = root;
  for (const Step& step : path) {
    YAML::Node next = std::holds_alternative<std::string>(step)
                          ? node[std::get<std::string>(step)]
                          : node[std::get<std::size_t>(step)];
    node.reset(next);
  }
  return node;
}

// `original`, changed by `change` at the last step of `path` (a non-empty path), as YAML.
std::string with_value(const YAML::Node& original, const Path& path,
                       const std::function<void(YAML::Node& parent, const Step& last)>& change) {
  YAML::Node root = YAML::Clone(original);
  Path parent_path(path.begin(), path.end() - 1);
  YAML::Node parent = at_path(root, parent_path);
  change(parent, path.back());
  return io::to_yaml(root);
}

YAML::Node scalar(const std::string& text) { return YAML::Node(text); }

void set_step(YAML::Node& parent, const Step& step, const YAML::Node& value) {
  if (const auto* key = std::get_if<std::string>(&step))
    parent[*key] = value;
  else
    parent[std::get<std::size_t>(step)] = value;
}

void drop_step(YAML::Node& parent, const Step& step) {
  if (const auto* key = std::get_if<std::string>(&step)) {
    parent.remove(*key);
    return;
  }
  YAML::Node kept(YAML::NodeType::Sequence);
  for (std::size_t i = 0; i < parent.size(); ++i)
    if (i != std::get<std::size_t>(step)) kept.push_back(parent[i]);
  kept.SetStyle(parent.Style());
  parent = kept;
}

void mutate_values(const YAML::Node& root, const YAML::Node& node, const Path& path,
                   std::vector<Mutant>& out) {
  const std::string where = path_text(path);
  const std::string key = last_key(path);
  const auto value_mutant = [&](const std::string& name, const YAML::Node& value, bool reject) {
    out.push_back({where + " = " + name,
                   with_value(root, path, [&](YAML::Node& parent, const Step& last) {
                     set_step(parent, last, value);
                   }),
                   reject});
  };
  if (!path.empty()) {
    // Any value may be replaced by a mapping of an unknown key, or dropped.
    YAML::Node bogus(YAML::NodeType::Map);
    bogus["zz_typo"] = 1;
    value_mutant("{zz_typo: 1}", bogus, true);
    out.push_back({where + " dropped", with_value(root, path, drop_step), false});
  }
  if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    const bool number = is_number(text);
    const bool typed = number || is_bool(text);
    value_mutant("abc", scalar("abc"), typed);
    value_mutant("\"\"", scalar(""), true);
    // Some keys take one value or a list of them (per channel, per stage).
    YAML::Node pair(YAML::NodeType::Sequence);
    pair.push_back(1);
    pair.push_back(2);
    pair.SetStyle(YAML::EmitterStyle::Flow);
    value_mutant("[1, 2]", pair, false);
    if (!number && !kFreeText.count(key)) value_mutant("sin(x", scalar("sin(x"), true);
    if (number) {
      value_mutant(".nan", scalar(".nan"), true);
      value_mutant("-3", scalar("-3"), in_key_set(kPositive, path));
      value_mutant("0", scalar("0"), false);
      value_mutant("1.5", scalar("1.5"), in_key_set(kInteger, path));
      value_mutant("1e300", scalar("1e300"), false);
      value_mutant("-1e300", scalar("-1e300"), false);
    }
    return;
  }
  if (!path.empty()) {
    value_mutant("abc", scalar("abc"), true);
    if (node.IsSequence()) value_mutant("[]", YAML::Node(YAML::NodeType::Sequence), false);
  }
  if (node.IsMap()) {
    // An unknown key beside the others, and each key misspelt.
    YAML::Node with_unknown = YAML::Clone(root);
    at_path(with_unknown, path)["zz_typo"] = 1;
    out.push_back({where + " + zz_typo", io::to_yaml(with_unknown), true});
    for (const auto& entry : node) {
      const std::string name = entry.first.Scalar();
      YAML::Node renamed = YAML::Clone(root);
      YAML::Node map = at_path(renamed, path);
      YAML::Node rebuilt(YAML::NodeType::Map);
      for (const auto& e : map)
        rebuilt[e.first.Scalar() == name ? name + "_typo" : e.first.Scalar()] = e.second;
      if (path.empty()) {
        renamed = rebuilt;
      } else {
        YAML::Node parent = at_path(renamed, Path(path.begin(), path.end() - 1));
        set_step(parent, path.back(), rebuilt);
      }
      out.push_back({where + (where.empty() ? "" : ".") + name + " renamed " + name + "_typo",
                     io::to_yaml(renamed), path.empty() || !kFreeNames.count(last_key(path))});
    }
    for (const auto& entry : node)
      mutate_values(root, entry.second, [&] {
        Path next = path;
        next.emplace_back(entry.first.Scalar());
        return next;
      }(), out);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i)
      mutate_values(root, node[i], [&] {
        Path next = path;
        next.emplace_back(i);
        return next;
      }(), out);
  }
}

// The file cut after every line and in the middle of every line that has text.
void truncations(const std::string& text, std::vector<Mutant>& out) {
  std::size_t start = 0;
  int line = 1;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string content = text.substr(start, end - start);
    const auto first = content.find_first_not_of(' ');
    if (first != std::string::npos && content[first] != '#') {
      const std::size_t middle = start + first + (content.size() - first) / 2;
      out.push_back({"cut in line " + std::to_string(line), text.substr(0, middle), false});
    }
    if (end < text.size())
      out.push_back({"cut after line " + std::to_string(line), text.substr(0, end + 1), false});
    start = end + 1;
    ++line;
  }
}

// "" when `e` is located as wanted, else what is wrong with it.
std::string location_problem(const io::ConfigError& e, const std::string& file, int lines) {
  const std::string what = e.what();
  if (what.rfind(file + ":", 0) != 0) return "does not start with the file name";
  std::size_t pos = file.size() + 1;
  const auto number = [&](int& value) {
    const std::size_t begin = pos;
    while (pos < what.size() && std::isdigit(static_cast<unsigned char>(what[pos]))) ++pos;
    if (pos == begin) return false;
    value = std::stoi(what.substr(begin, pos - begin));
    return true;
  };
  int line = 0, column = 0;
  if (!number(line) || what.substr(pos, 1) != ":") return "no line number";
  ++pos;
  if (!number(column) || what.substr(pos, 2) != ": ") return "no column number";
  pos += 2;
  if (line < 1 || line > lines + 1 || column < 1) return "line or column out of the file";
  const std::string& message = e.message();
  const bool at_root = message.rfind("YAML syntax error", 0) == 0 ||
                       message.rfind("expected a mapping of keys at the top level", 0) == 0 ||
                       message.rfind("expected one YAML document", 0) == 0;
  if (e.key_path().empty()) return at_root ? "" : "no key path";
  if (what.compare(pos, e.key_path().size() + 2, e.key_path() + ": ") != 0)
    return "key path not after the location";
  return "";
}

// FNV-1a: a hash that is the same on every platform, so that a sample of mutants is too.
std::uint64_t fnv1a(const std::string& text) {
  std::uint64_t hash = 14695981039346656037ull;
  for (unsigned char c : text) hash = (hash ^ c) * 1099511628211ull;
  return hash;
}

// Configs whose validation takes tens of ms to a second (it reads posed images or a mesh,
// or computes a finite-difference reference) test 1 in N of their mutants; the others test
// all. The sample depends on the mutants' names only, never on timing, so that every run
// tests the same mutants (a sample sized by the time one validation took differed between a
// busy and a quiet machine, and a failure showed on one only). A config missing here is
// tested whole: slow, never wrong. NFIELD_ALL_MUTANTS=1 tests every mutant (about 17 min).
int sample_stride(const std::string& config) {
  static const std::map<std::string, int> kSampleStride = {
      {"accuracy_wave_2d", 128},  // ~0.9 s a validation (the FD reference)
      {"wave_2d", 128},           // ~0.9 s
      {"sdf_bunny", 128},         // ~0.8 s (the mesh and its signed distances)
      {"sdf_bunny_bacon", 128},   // the same mesh
      {"poisson_bunny", 32},      // ~2 s (the mesh's smooth distance: a spline fit)
      {"allen_cahn_1d", 4},       // ~0.13 s (the ETDRK4 reference)
      {"sdf_kitten", 16},         // ~140 ms
      {"fit_video", 8},           // ~80 ms
      {"fit_image_acorn", 128},   // ~1 s (a 4096² WebP picture)
      {"autoint_bunny", 8},       // ~40 ms
      {"nerf_bunny", 8},          // ~30 ms (posed images)
      {"nerf_bunny_hash_grid", 8},
      {"nerf_bunny_mip", 8},
      {"nerf_bunny_quadrature", 8},
      {"nerf_bunny_appearance", 8},  // ~40 ms (posed images, recoloured)
      {"nerf_bunny_recoloured", 8},
      {"poisson_image_laplacian", 4},  // ~18 ms
      {"poisson_family", 8},           // ~0.3 s (36 instances of 16-term expressions)
      {"occupancy_bunny_acorn", 16},   // ~0.6 s (the mesh's closedness and self-intersection checks)
      {"deepsdf_meshes", 16},          // ~0.2 s (five meshes)
      {"navier_stokes_cylinder", 4},   // ~15 ms, but 1,276 mutants
      {"burgers_identify", 4},         // ~22 ms (the measurements file)
  };
  const auto it = kSampleStride.find(config);
  return it == kSampleStride.end() ? 1 : it->second;
}

class ConfigMutation : public ::testing::TestWithParam<std::string> {};

TEST_P(ConfigMutation, RejectionsAreLocatedAndBrokenConfigsRejected) {
  const std::filesystem::path original = kConfigs / (GetParam() + ".yaml");
  std::ifstream in(original);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  const YAML::Node root = YAML::Load(text);

  std::vector<Mutant> mutants;
  mutate_values(root, root, {}, mutants);
  truncations(text, mutants);

  const std::filesystem::path dir = testutil::scratch_dir("solvers");
  const std::filesystem::path file = dir / (GetParam() + ".yaml");
  const std::filesystem::path out_dir = dir / "out";
  // NFIELD_ALL_MUTANTS=1 tests every mutant of every config.
  const bool all = std::getenv("NFIELD_ALL_MUTANTS") != nullptr;
  const auto every = static_cast<std::uint64_t>(all ? 1 : sample_stride(GetParam()));
  int tested = 0, accepted = 0, located = 0, unlocated = 0, wrongly_accepted = 0;
  const auto start = std::chrono::steady_clock::now();
  for (const Mutant& mutant : mutants) {
    if (fnv1a(mutant.name) % every != 0) continue;
    ++tested;
    std::ofstream(file, std::ios::trunc) << mutant.text;
    const int lines = static_cast<int>(std::count(mutant.text.begin(), mutant.text.end(), '\n'));
    try {
      load_run(file, {}, out_dir, kConfigs);
      ++accepted;
      if (mutant.must_reject) {
        ++wrongly_accepted;
        ADD_FAILURE() << GetParam() << ": " << mutant.name << ": accepted";
      }
    } catch (const io::ConfigError& e) {
      const std::string problem = location_problem(e, file.string(), lines);
      if (problem.empty()) {
        ++located;
      } else {
        ++unlocated;
        ADD_FAILURE() << GetParam() << ": " << mutant.name << ": " << problem << ": " << e.what();
      }
    } catch (const std::exception& e) {
      ++unlocated;
      ADD_FAILURE() << GetParam() << ": " << mutant.name << ": not a ConfigError: " << e.what();
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%s: %d of %zu mutants, %d accepted, %d rejected located, %d rejected unlocated, "
              "%d invalid accepted (%.2f s, %.1f ms a validation)\n",
              GetParam().c_str(), tested, mutants.size(), accepted, located, unlocated,
              wrongly_accepted, seconds, 1e3 * seconds / std::max(tested, 1));
}

std::vector<std::string> shipped_configs() {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(kConfigs))
    if (entry.path().extension() == ".yaml") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

INSTANTIATE_TEST_SUITE_P(Shipped, ConfigMutation, ::testing::ValuesIn(shipped_configs()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace nfield::solvers
