#include <paco/common/error.h>
#include <paco/encoding/model_config.h>

#include <cctype>
#include <cmath>
#include <functional>
#include <iomanip>
#include <map>
#include <sstream>

namespace paco {
namespace {

// One reflective table of fields keeps toJson, fromJson, == and firstDifference in step.
struct Field {
  const char* key;
  std::function<std::string(const ModelConfig&)> write;  // JSON value text
  std::function<void(ModelConfig&, const std::string&)> read;  // from JSON value text
};

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

int parseInt(const std::string& key, const std::string& v) {
  try {
    std::size_t used = 0;
    long value = std::stol(v, &used);
    if (used != v.size()) throw std::invalid_argument(v);
    return static_cast<int>(value);
  } catch (const std::exception&) {
    throw InvalidInputError("ModelConfig: '" + key + "' must be an integer, got '" + v + "'");
  }
}

double parseDouble(const std::string& key, const std::string& v) {
  try {
    std::size_t used = 0;
    double value = std::stod(v, &used);
    if (used != v.size()) throw std::invalid_argument(v);
    return value;
  } catch (const std::exception&) {
    throw InvalidInputError("ModelConfig: '" + key + "' must be a number, got '" + v + "'");
  }
}

std::string parseString(const std::string& key, const std::string& v) {
  if (v.size() < 2 || v.front() != '"' || v.back() != '"')
    throw InvalidInputError("ModelConfig: '" + key + "' must be a string, got " + v);
  std::string out;
  for (std::size_t i = 1; i + 1 < v.size(); ++i) {
    if (v[i] == '\\' && i + 2 < v.size()) ++i;
    out += v[i];
  }
  return out;
}

std::vector<int> parseIntList(const std::string& key, const std::string& v) {
  if (v.size() < 2 || v.front() != '[' || v.back() != ']')
    throw InvalidInputError("ModelConfig: '" + key + "' must be a list of integers, got " + v);
  std::vector<int> out;
  std::stringstream items(v.substr(1, v.size() - 2));
  std::string item;
  while (std::getline(items, item, ',')) {
    item.erase(0, item.find_first_not_of(" \t\n\r"));
    item.erase(item.find_last_not_of(" \t\n\r") + 1);
    if (!item.empty()) out.push_back(parseInt(key, item));
  }
  return out;
}

#define PACO_INT_FIELD(name)                                                          \
  Field {                                                                             \
    #name, [](const ModelConfig& c) { return std::to_string(c.name); },               \
        [](ModelConfig& c, const std::string& v) { c.name = parseInt(#name, v); }     \
  }

const std::vector<Field>& fields() {
  static const std::vector<Field> table = {
      Field{"name", [](const ModelConfig& c) { return quote(c.name); },
            [](ModelConfig& c, const std::string& v) { c.name = parseString("name", v); }},
      PACO_INT_FIELD(num_centres),
      PACO_INT_FIELD(knn_k),
      PACO_INT_FIELD(input_embedding),
      Field{"edge_conv_widths",
            [](const ModelConfig& c) {
              std::string s = "[";
              for (std::size_t i = 0; i < c.edge_conv_widths.size(); ++i)
                s += (i ? ", " : "") + std::to_string(c.edge_conv_widths[i]);
              return s + "]";
            },
            [](ModelConfig& c, const std::string& v) {
              c.edge_conv_widths = parseIntList("edge_conv_widths", v);
            }},
      PACO_INT_FIELD(group_norm_groups),
      PACO_INT_FIELD(width),
      PACO_INT_FIELD(heads),
      Field{"mlp_ratio",
            [](const ModelConfig& c) {
              std::ostringstream s;
              s << std::setprecision(17) << c.mlp_ratio;
              return s.str();
            },
            [](ModelConfig& c, const std::string& v) { c.mlp_ratio = parseDouble("mlp_ratio", v); }},
      PACO_INT_FIELD(position_hidden),
      PACO_INT_FIELD(encoder_depth),
      PACO_INT_FIELD(encoder_graph_k),
      PACO_INT_FIELD(normal_hidden),
      PACO_INT_FIELD(plane_slots),
      PACO_INT_FIELD(global_width),
      PACO_INT_FIELD(generated_queries),
      PACO_INT_FIELD(kept_queries),
      PACO_INT_FIELD(decoder_depth),
      PACO_INT_FIELD(points_per_plane),
      PACO_INT_FIELD(distributor_hidden),
      Field{"distributor", [](const ModelConfig& c) { return quote(c.distributor); },
            [](ModelConfig& c, const std::string& v) {
              c.distributor = parseString("distributor", v);
            }},
      Field{"input_orientation", [](const ModelConfig& c) { return quote(c.input_orientation); },
            [](ModelConfig& c, const std::string& v) {
              c.input_orientation = parseString("input_orientation", v);
            }},
  };
  return table;
}
#undef PACO_INT_FIELD

void require(bool ok, const std::string& message) {
  if (!ok) throw InvalidInputError("ModelConfig: " + message);
}

}  // namespace

ModelConfig ModelConfig::preset(const std::string& name) {
  ModelConfig c;  // the defaults are the paper's reference sizes
  if (name == "paper") return c;
  if (name == "cpu") {
    // Chosen by measurement on 2 cores (doc/benchmarks.md): batch-1 inference of a 2,048-point
    // cloud well under 30 ms and a training step at batch 16 fast enough for hours of training.
    c.name = "cpu";
    c.knn_k = 16;
    c.input_embedding = 8;
    c.edge_conv_widths = {32, 64, 64, 128};
    c.width = 192;
    c.heads = 6;
    c.mlp_ratio = 2.0;
    c.position_hidden = 64;
    c.encoder_depth = 2;
    c.encoder_graph_k = 8;
    c.normal_hidden = 64;
    c.global_width = 384;
    c.decoder_depth = 4;
    c.points_per_plane = 256;
    c.distributor_hidden = 384;
    return c;
  }
  throw InvalidInputError("ModelConfig: unknown preset '" + name + "'; use 'paper' or 'cpu'");
}

std::vector<std::string> ModelConfig::presetNames() { return {"paper", "cpu"}; }

void ModelConfig::validate() const {
  require(num_centres >= 1, "num_centres must be >= 1 (got " + std::to_string(num_centres) + ")");
  require(knn_k >= 1, "knn_k must be >= 1 (got " + std::to_string(knn_k) + ")");
  require(input_embedding >= 1, "input_embedding must be >= 1");
  require(!edge_conv_widths.empty(), "edge_conv_widths must list at least one layer");
  require(group_norm_groups >= 1, "group_norm_groups must be >= 1");
  for (int w : edge_conv_widths)
    require(w >= 1 && w % group_norm_groups == 0,
            "every edge_conv_widths entry must be >= 1 and divisible by group_norm_groups (" +
                std::to_string(group_norm_groups) + "), got " + std::to_string(w));
  require(heads >= 1, "heads must be >= 1");
  require(width >= 8 && width % heads == 0,
          "width must be >= 8 and divisible by heads (got width " + std::to_string(width) +
              ", heads " + std::to_string(heads) + ")");
  require(mlp_ratio > 0.0 && std::isfinite(mlp_ratio), "mlp_ratio must be > 0");
  require(position_hidden >= 1, "position_hidden must be >= 1");
  require(encoder_depth >= 0, "encoder_depth must be >= 0");
  require(encoder_graph_k >= 0, "encoder_graph_k must be >= 0 (0 turns graph attention off)");
  require(normal_hidden >= 1, "normal_hidden must be >= 1");
  require(plane_slots >= 1, "plane_slots (K) must be >= 1");
  require(global_width >= 1, "global_width must be >= 1");
  require(kept_queries >= 1, "kept_queries (M) must be >= 1");
  // Padded input slots are never kept, so the generated queries alone must be able to fill M.
  require(generated_queries >= kept_queries,
          "generated_queries must be >= kept_queries (M), got " +
              std::to_string(generated_queries) + " < " + std::to_string(kept_queries));
  require(decoder_depth >= 1, "decoder_depth must be >= 1");
  require(points_per_plane >= 1, "points_per_plane must be >= 1");
  require(distributor_hidden >= 1, "distributor_hidden must be >= 1");
  require(distributor == "projected" || distributor == "polar",
          "distributor must be 'projected' or 'polar' (got '" + distributor + "')");
  require(input_orientation == "as-is" || input_orientation == "seen-planes",
          "input_orientation must be 'as-is' or 'seen-planes' (got '" + input_orientation + "')");
}

std::string ModelConfig::toJson() const {
  std::string out = "{\n";
  const auto& table = fields();
  for (std::size_t i = 0; i < table.size(); ++i)
    out += "  " + quote(table[i].key) + ": " + table[i].write(*this) +
           (i + 1 < table.size() ? ",\n" : "\n");
  return out + "}\n";
}

ModelConfig ModelConfig::fromJson(const std::string& json) {
  // A flat object: "key": value, with values that are numbers, strings or lists of integers.
  std::size_t pos = json.find('{');
  const std::size_t end = json.rfind('}');
  if (pos == std::string::npos || end == std::string::npos || end < pos)
    throw InvalidInputError("ModelConfig: not a JSON object");
  std::map<std::string, const Field*> by_key;
  for (const Field& f : fields()) by_key[f.key] = &f;
  ModelConfig config;
  ++pos;
  auto skipSpace = [&] {
    while (pos < end && std::isspace(static_cast<unsigned char>(json[pos]))) ++pos;
  };
  while (true) {
    skipSpace();
    if (pos >= end) break;
    if (json[pos] != '"') throw InvalidInputError("ModelConfig: expected a quoted key in JSON");
    const std::size_t key_end = json.find('"', pos + 1);
    if (key_end == std::string::npos || key_end > end)
      throw InvalidInputError("ModelConfig: unterminated key in JSON");
    const std::string key = json.substr(pos + 1, key_end - pos - 1);
    pos = json.find(':', key_end);
    if (pos == std::string::npos || pos > end)
      throw InvalidInputError("ModelConfig: missing ':' after '" + key + "'");
    ++pos;
    skipSpace();
    std::size_t value_end = pos;
    if (pos < end && json[pos] == '"') {
      value_end = pos + 1;
      while (value_end < end && json[value_end] != '"') value_end += json[value_end] == '\\' ? 2 : 1;
      ++value_end;
    } else if (pos < end && json[pos] == '[') {
      value_end = json.find(']', pos);
      if (value_end == std::string::npos || value_end > end)
        throw InvalidInputError("ModelConfig: unterminated list for '" + key + "'");
      ++value_end;
    } else {
      while (value_end < end && json[value_end] != ',' &&
             !std::isspace(static_cast<unsigned char>(json[value_end])))
        ++value_end;
    }
    if (value_end > end) throw InvalidInputError("ModelConfig: malformed value for '" + key + "'");
    const std::string value = json.substr(pos, value_end - pos);
    auto it = by_key.find(key);
    if (it == by_key.end()) throw InvalidInputError("ModelConfig: unknown key '" + key + "'");
    it->second->read(config, value);
    pos = value_end;
    skipSpace();
    if (pos < end && json[pos] == ',') ++pos;
  }
  return config;
}

bool ModelConfig::operator==(const ModelConfig& other) const {
  return name == other.name && firstDifference(other).empty();
}

std::string ModelConfig::firstDifference(const ModelConfig& other) const {
  for (const Field& f : fields()) {
    if (std::string(f.key) == "name") continue;
    const std::string a = f.write(*this), b = f.write(other);
    if (a != b) return std::string(f.key) + ": " + a + " vs " + b;
  }
  return "";
}

}  // namespace paco
