#include <exception>
#include <new>

#include "core/errors.h"
#include "core/version.h"
#include "io/output_folder.h"
#include "iphong/commands.h"
#include "iphong/console.h"

namespace {

// The subcommand a failed parse was working on, for "see iphong CMD --help".
std::string ParsedCommand(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands()) return sub->get_name();
  return "";
}

int Fail(const std::string& message, int code) {
  if (iphong::cli::Interrupted()) iphong::cli::AwaitInterrupt();
  std::fprintf(iphong::cli::Err(), "iphong: error: %s\n",
               iphong::OneLine(iphong::io::WithoutStagingNames(message)).c_str());
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  iphong::cli::SetUpConsole();
  CLI::App app{
      "iphong: surface normals, heights and materials from photographs by inverting the Phong "
      "reflection model, and a forward Phong renderer with exact ground truth."};
  app.name("iphong");
  app.set_version_flag("--version", std::string("iphong ") + iphong::kVersion);
  app.require_subcommand(1);
  app.footer(iphong::cli::kExitCodes);
  iphong::cli::AddAllCommands(app);
  if (argc == 1) {  // bare `iphong`: what it can do, not "A subcommand is required"
    std::fputs(app.help().c_str(), stdout);
    return 0;
  }
  // CLI11 reports an unknown command as "A subcommand is required"; say what was typed.
  if (argc > 1 && argv[1][0] != '-') {
    std::string known;
    bool found = false;
    for (const CLI::App* sub : app.get_subcommands({})) {
      found |= sub->get_name() == argv[1];
      known += (known.empty() ? "" : ", ") + sub->get_name();
    }
    if (!found) {
      return Fail(std::string(argv[1]) + ": no such command (" + known + ")",
                  iphong::cli::kExitUsage);
    }
  }
  int code = 0;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    const std::string command = ParsedCommand(app);
    code = Fail((command.empty() ? "" : command + ": ") + e.what() + " (see iphong " +
                    (command.empty() ? "" : command + " ") + "--help)",
                iphong::cli::kExitUsage);
  } catch (const iphong::ResourceError& e) {
    code = Fail(e.what(), iphong::cli::kExitResources);
  } catch (const iphong::OutputError& e) {
    code = Fail(e.what(), iphong::cli::kExitOutput);
  } catch (const std::bad_alloc&) {
    code =
        Fail("out of memory (lower --memory-limit, or free memory)", iphong::cli::kExitResources);
  } catch (const std::invalid_argument& e) {
    code = Fail(e.what(), iphong::cli::kExitInput);
  } catch (const std::logic_error& e) {
    code = Fail(std::string("internal error (please report it): ") + e.what(),
                iphong::cli::kExitInternal);
  } catch (const std::exception& e) {
    code = Fail(e.what(), iphong::cli::kExitInput);
  }
  if (std::fflush(stdout) != 0 && code == 0) code = iphong::cli::kExitOutput;
  // An interrupt that came as the run finished: its watcher says what is left and exits.
  if (iphong::cli::Interrupted()) iphong::cli::AwaitInterrupt();
  return code;
}
