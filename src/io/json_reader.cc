#include "io/json_reader.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/errors.h"

namespace iphong::io {

namespace {

// Where the parser is, for naming a repeated key: each open container, with an object's keys so
// far and the one being read, or an array's element index.
struct OpenContainer {
  bool array = false;
  long index = -1;
  std::string key;
  std::set<std::string> keys;
};

std::string PathOf(const std::vector<OpenContainer>& open) {
  std::string path;
  for (std::size_t i = 0; i + 1 < open.size(); ++i) {
    path += open[i].array ? "[" + std::to_string(open[i].index) + "]"
                          : (path.empty() ? "" : ".") + open[i].key;
  }
  return path;
}

}  // namespace

nlohmann::json JsonReader::Parse(const std::string& text, const std::string& file) {
  std::vector<OpenContainer> open;
  using Event = nlohmann::json::parse_event_t;
  const nlohmann::json::parser_callback_t track = [&](int, Event event, nlohmann::json& parsed) {
    if (event == Event::object_start || event == Event::array_start || event == Event::value) {
      if (!open.empty() && open.back().array) ++open.back().index;
    }
    if (event == Event::object_start || event == Event::array_start) {
      open.push_back({event == Event::array_start, -1, "", {}});
    } else if (event == Event::object_end || event == Event::array_end) {
      if (!open.empty()) open.pop_back();
    } else if (event == Event::key && !open.empty() && parsed.is_string()) {
      OpenContainer& object = open.back();
      object.key = parsed.get<std::string>();
      if (!object.keys.insert(object.key).second) {
        const std::string where = PathOf(open);
        throw JsonError(OneLine(file + ": " + (where.empty() ? "" : where + ": ") + "the key '" +
                                object.key +
                                "' is given twice in one object; JSON keeps only one of "
                                "them: remove the other"));
      }
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text, track);
  } catch (const nlohmann::json::exception& e) {
    // nlohmann's messages: "[json.exception.parse_error.101] parse error at line 3, column 5:
    // ...", "[json.exception.out_of_range.406] number overflow parsing '1e400'".
    std::string what = e.what();
    const auto start = what.find("] ");
    what = start == std::string::npos ? what : what.substr(start + 2);
    if (what.rfind("number overflow", 0) == 0) what = "parse error: " + what;
    throw std::runtime_error(OneLine(file + ": " + what));
  }
}

void JsonReader::Fail(const std::string& message) const {
  throw JsonError(OneLine(where() + ": " + message));
}

bool JsonReader::Has(const std::string& key) const {
  return value_.is_object() && value_.contains(key);
}

JsonReader JsonReader::Field(const std::string& key) const {
  if (!value_.is_object()) Fail("expected an object");
  if (!value_.contains(key)) Fail("missing field '" + key + "'");
  return JsonReader(value_.at(key), file_, path_.empty() ? key : path_ + "." + key);
}

JsonReader JsonReader::At(std::size_t index) const {
  if (!value_.is_array() || index >= value_.size()) Fail("expected an array");
  return JsonReader(value_.at(index), file_, path_ + "[" + std::to_string(index) + "]");
}

std::size_t JsonReader::Size() const {
  if (!value_.is_array()) Fail("expected an array");
  return value_.size();
}

double JsonReader::Number() const {
  if (!value_.is_number()) Fail("expected a number");
  const double v = value_.get<double>();
  if (!std::isfinite(v)) Fail("expected a finite number");
  return v;
}

double JsonReader::Number(const std::string& key, double fallback) const {
  return Has(key) ? Field(key).Number() : fallback;
}

int JsonReader::Integer(const std::string& key, int fallback) const {
  if (!Has(key)) return fallback;
  return Field(key).Integer();
}

int JsonReader::Integer() const {
  // Read wide and range-checked: get<int>() of 4294967328 would wrap to 32. Whole floats (256.0,
  // as some writers print) are integers too.
  double v = 0;
  if (value_.is_number_unsigned()) {
    v = static_cast<double>(value_.get<std::uint64_t>());
  } else if (value_.is_number_integer()) {
    v = static_cast<double>(value_.get<std::int64_t>());
  } else if (value_.is_number_float() && std::isfinite(value_.get<double>()) &&
             value_.get<double>() == std::floor(value_.get<double>())) {
    v = value_.get<double>();
  } else {
    Fail("expected an integer");
  }
  if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) {
    Fail("integer out of range");
  }
  return static_cast<int>(v);
}

bool JsonReader::Bool(const std::string& key, bool fallback) const {
  if (!Has(key)) return fallback;
  const JsonReader f = Field(key);
  if (!f.value_.is_boolean()) f.Fail("expected true or false");
  return f.value_.get<bool>();
}

std::string JsonReader::String() const {
  if (!value_.is_string()) Fail("expected a string");
  return value_.get<std::string>();
}

std::string JsonReader::String(const std::string& key, const std::string& fallback) const {
  return Has(key) ? Field(key).String() : fallback;
}

Vec3d JsonReader::Vector3() const {
  if (!value_.is_array() || value_.size() != 3) Fail("expected 3 numbers");
  return Vec3d(At(0).Number(), At(1).Number(), At(2).Number());
}

Vec3d JsonReader::Rgb() const {
  if (value_.is_number()) return Vec3d::Constant(Number());
  return Vector3();
}

Vec3d JsonReader::Rgb(const std::string& key, const Vec3d& fallback) const {
  return Has(key) ? Field(key).Rgb() : fallback;
}

Vec3d JsonReader::Vector3(const std::string& key, const Vec3d& fallback) const {
  return Has(key) ? Field(key).Vector3() : fallback;
}

void JsonReader::OnlyKeys(const std::set<std::string>& known) const {
  if (!value_.is_object()) Fail("expected an object");
  for (const auto& item : value_.items()) {
    if (!known.count(item.key())) {
      std::string valid;
      for (const std::string& k : known) valid += (valid.empty() ? "" : ", ") + k;
      Fail("unknown field '" + item.key() + "' (valid: " + valid + ")");
    }
  }
}

}  // namespace iphong::io
