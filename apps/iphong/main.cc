#include <exception>
#include <iostream>

#include "core/version.h"
#include "iphong/commands.h"

int main(int argc, char** argv) {
  CLI::App app{
      "iphong: surface normals, heights and materials from photographs by inverting the Phong "
      "reflection model, and a forward Phong renderer with exact ground truth."};
  app.set_version_flag("--version", std::string("iphong ") + iphong::kVersion);
  app.require_subcommand(1);
  iphong::cli::AddAllCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "iphong: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
