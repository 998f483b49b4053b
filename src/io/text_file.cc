#include "io/text_file.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace iphong::io {

std::string ReadTextFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error(path + ": cannot open");
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

void WriteTextFile(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  if (!file) throw std::runtime_error(path + ": cannot write");
}

}  // namespace iphong::io
