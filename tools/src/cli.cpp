#include <CLI/CLI.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/tools/cli.hpp>
#include <iostream>

#include "commands.hpp"

namespace clutterscope::tools {

namespace {
constexpr int kExitUsage = 2;
constexpr int kExitBadInput = 3;
constexpr int kExitRuntime = 4;
}  // namespace

int run_cli(int argc, char** argv) {
  CLI::App app{
      "clutterscope: visibility and pose-belief analysis of cluttered scenes (BOP datasets)"};
  app.set_version_flag("--version", std::string("clutterscope ") + CLUTTERSCOPE_VERSION);
  app.require_subcommand(1);
  int exit_code = 0;
  add_render_command(app, &exit_code);
  add_visibility_command(app, &exit_code);
  add_bench_visibility_command(app, &exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int code = app.exit(error);
    return code == 0 ? 0 : kExitUsage;
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
