// Whole text files in and out; errors name the file.
#pragma once

#include <string>

namespace iphong::io {

// Throws std::runtime_error "PATH: cannot open".
std::string ReadTextFile(const std::string& path);
// Throws std::runtime_error "PATH: cannot write".
void WriteTextFile(const std::string& path, const std::string& text);

}  // namespace iphong::io
