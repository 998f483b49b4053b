// The iphong subcommands. Each one adds itself to the CLI11 app: parse flags into an options
// struct, make one library call, write the outputs.
#pragma once

#include <CLI/CLI.hpp>

namespace iphong::cli {

void AddDemoCommand(CLI::App& app);
void AddMaterialsCommand(CLI::App& app);
void AddRenderCommand(CLI::App& app);
void AddNormalsCommand(CLI::App& app);  // normals and eval
void AddIntegrateCommand(CLI::App& app);

// Every subcommand, in the order `iphong --help` lists them. New commands are added here only.
inline void AddAllCommands(CLI::App& app) {
  AddDemoCommand(app);
  AddRenderCommand(app);
  AddNormalsCommand(app);
  AddIntegrateCommand(app);
  AddMaterialsCommand(app);
}

}  // namespace iphong::cli
