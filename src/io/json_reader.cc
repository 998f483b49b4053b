#include "io/json_reader.h"

#include <cmath>

namespace iphong::io {

nlohmann::json JsonReader::Parse(const std::string& text, const std::string& file) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // nlohmann's message: "[json.exception.parse_error.101] parse error at line 3, column 5: ..."
    std::string what = e.what();
    const auto start = what.find("parse error");
    throw std::runtime_error(file + ": " +
                             (start == std::string::npos ? what : what.substr(start)));
  }
}

void JsonReader::Fail(const std::string& message) const {
  throw JsonError(where() + ": " + message);
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
  const JsonReader f = Field(key);
  if (!f.value_.is_number_integer()) f.Fail("expected an integer");
  return f.value_.get<int>();
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
    if (!known.count(item.key())) Fail("unknown field '" + item.key() + "'");
  }
}

}  // namespace iphong::io
