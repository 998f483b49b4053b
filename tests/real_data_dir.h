// Where the tests find the real photometric-stereo data (DiLiGenT, UW): $IPHONG_DATA_DIR, else
// ../shared/data beside the checkout. Tests skip with a message when it is absent.
#pragma once

#include <cstdlib>
#include <string>

namespace iphong::test {

inline std::string RealDataDir() {
  const char* env = std::getenv("IPHONG_DATA_DIR");
  return env ? env : IPHONG_SOURCE_DIR "/../shared/data";
}

}  // namespace iphong::test
