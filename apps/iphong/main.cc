#include <algorithm>
#include <exception>
#include <new>
#include <string>
#include <vector>

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

// Edit distance between two option names (insertions, deletions, substitutions).
std::size_t Distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// " (did you mean --lights?)" for a mistyped long option of the command, else "".
std::string Suggestion(const CLI::App& app, const std::string& command, int argc, char** argv) {
  const CLI::App* sub = nullptr;
  for (const CLI::App* s : app.get_subcommands({}))
    if (s->get_name() == command) sub = s;
  if (!sub) return "";
  std::vector<std::string> names;
  for (const CLI::Option* option : sub->get_options())
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
  std::string text;
  for (int i = 2; i < argc; ++i) {
    std::string arg = argv[i];
    arg = arg.substr(0, arg.find('='));
    if (arg.rfind("--", 0) != 0 || arg.size() < 4 ||
        std::find(names.begin(), names.end(), arg) != names.end())
      continue;
    std::string best;
    std::size_t best_distance = 3;  // at most two edits away
    for (const std::string& name : names) {
      const std::size_t d = Distance(arg, name);
      if (d < best_distance) best_distance = d, best = name;
    }
    if (!best.empty()) text += (text.empty() ? " (" : "; ") + arg + ": did you mean " + best + "?";
  }
  return text.empty() ? "" : text + ")";
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
    code = Fail((command.empty() ? "" : command + ": ") + e.what() +
                    Suggestion(app, command, argc, argv) + " (see iphong " +
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
