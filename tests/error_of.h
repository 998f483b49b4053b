// The message a call throws, for tests that check the exact one-line error.
#pragma once

#include <exception>
#include <functional>
#include <string>

namespace iphong::test {

inline std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace iphong::test
