// Typed access to a JSON document with errors that say where: "scene.json: objects[0].radius:
// expected a number > 0". Unknown fields are errors too, so a typo never passes silently.
#pragma once

#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>

#include "core/types.h"

namespace iphong::io {

// An error already located in a JSON document ("file: path: message").
struct JsonError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class JsonReader {
 public:
  JsonReader(const nlohmann::json& value, std::string file, std::string path = "")
      : value_(value), file_(std::move(file)), path_(std::move(path)) {}

  // Parses text; a syntax error names the file, line and column, and a key given twice in one
  // object is an error naming it (JSON keeps one of the two silently: which one a user meant is
  // not in the file).
  static nlohmann::json Parse(const std::string& text, const std::string& file);

  const nlohmann::json& value() const { return value_; }
  bool Has(const std::string& key) const;
  JsonReader Field(const std::string& key) const;  // required
  JsonReader At(std::size_t index) const;
  std::size_t Size() const;  // array length (error if not an array)

  double Number() const;
  double Number(const std::string& key, double fallback) const;
  int Integer() const;  // an int; larger values are an error, never wrapped
  int Integer(const std::string& key, int fallback) const;
  bool Bool(const std::string& key, bool fallback) const;
  std::string String() const;
  std::string String(const std::string& key, const std::string& fallback) const;
  // A 3-vector; an RGB triple may also be given as one number (grey).
  Vec3d Vector3() const;
  Vec3d Rgb() const;
  Vec3d Rgb(const std::string& key, const Vec3d& fallback) const;
  Vec3d Vector3(const std::string& key, const Vec3d& fallback) const;

  // Throws unless every key of this object is in `known`.
  void OnlyKeys(const std::set<std::string>& known) const;
  [[noreturn]] void Fail(const std::string& message) const;
  std::string where() const { return path_.empty() ? file_ : file_ + ": " + path_; }

 private:
  const nlohmann::json& value_;
  std::string file_;
  std::string path_;
};

}  // namespace iphong::io
