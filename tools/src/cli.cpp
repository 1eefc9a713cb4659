#include <CLI/CLI.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/tools/batch.hpp>
#include <clutterscope/tools/cli.hpp>
#include <iostream>

#include "commands.hpp"

namespace clutterscope::tools {

namespace {

constexpr int kExitUsage = 2;
constexpr int kExitBadInput = 3;
constexpr int kExitRuntime = 4;

// One line per command, in the order `clutterscope --help` lists them.
void add_commands(CLI::App& app, int* exit_code) {
  add_render_command(app, exit_code);
  add_visibility_command(app, exit_code);
  add_merge_command(app, exit_code);
  add_bench_visibility_command(app, exit_code);
}

void describe_app(CLI::App& app) {
  app.description(
      "clutterscope: visibility and pose-belief analysis of cluttered scenes (BOP datasets).\n"
      "Run `clutterscope COMMAND --help` for a command's options.");
  app.set_version_flag("--version", std::string("clutterscope ") + CLUTTERSCOPE_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Exit codes: 0 ok, 1 some images failed under --keep-going (listed in summary.json),\n"
      "2 usage error, 3 bad input data (the message names file, scene, image and field),\n"
      "4 rendering or runtime failure.");
  app.get_formatter()->column_width(28);
}

}  // namespace

std::vector<std::string> command_names() {
  CLI::App app;
  int exit_code = 0;
  add_commands(app, &exit_code);
  std::vector<std::string> names;
  for (const CLI::App* command : app.get_subcommands({})) names.push_back(command->get_name());
  return names;
}

int run_cli(int argc, char** argv) {
  CLI::App app;
  describe_app(app);
  int exit_code = 0;
  add_commands(app, &exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int code = app.exit(error);
    return code == 0 ? 0 : kExitUsage;
  } catch (const UsageError& error) {
    std::cerr << "error: " << error.what() << "\n";
    return kExitUsage;
  } catch (const datasets::DatasetError& error) {
    std::cerr << "error: " << error.what() << "\n";
    return kExitBadInput;
  } catch (const render::RenderError& error) {
    std::cerr << "render error: " << error.what() << "\n";
    return kExitRuntime;
  } catch (const std::exception& error) {
    std::cerr << "error: " << error.what() << "\n";
    return kExitRuntime;
  }
  return exit_code;
}

}  // namespace clutterscope::tools
