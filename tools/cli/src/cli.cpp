#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/build_info.hpp>
#include <clutterscope/cli/cli.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "commands.hpp"

namespace clutterscope::cli {

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
  add_generate_command(app, exit_code);
  add_detect_command(app, exit_code);
  add_graph_command(app, exit_code);
  add_estimate_command(app, exit_code);
  add_bench_estimate_command(app, exit_code);
  add_evaluate_command(app, exit_code);
  add_bench_evaluate_command(app, exit_code);
  add_bench_calibration_command(app, exit_code);
  add_report_command(app, exit_code);
  add_thresholds_command(app, exit_code);
  add_simulate_command(app, exit_code);
  add_sensor_fit_command(app, exit_code);
  add_notebook_command(app, exit_code);
}

constexpr std::size_t kHelpWidth = 100;

// Word-wraps each line of `text` to `width` columns.
std::string wrap(const std::string& text, std::size_t width) {
  std::string wrapped;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    std::string line = text.substr(start, end - start);
    while (line.size() > width) {
      std::size_t cut = line.rfind(' ', width);
      if (cut == std::string::npos || cut == 0) cut = line.find(' ');
      if (cut == std::string::npos) break;
      wrapped += line.substr(0, cut) + "\n";
      line = line.substr(cut + 1);
    }
    wrapped += line + "\n";
    start = end + 1;
  }
  return wrapped;
}

// Up to the first line break or ". " followed by a capital ("Eq. 10" does not end it).
std::string first_sentence(const std::string& text) {
  std::size_t end = text.find('\n');
  for (std::size_t dot = text.find(". "); dot != std::string::npos && dot < end;
       dot = text.find(". ", dot + 1)) {
    if (dot + 2 < text.size() && std::isupper(static_cast<unsigned char>(text[dot + 2]))) {
      end = dot;
      break;
    }
  }
  return text.substr(0, end);
}

// Lists each command with the first sentence of its description (the full text is in the
// command's own --help) and wraps long descriptions.
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_subcommand(const CLI::App* command) const override {
    std::string summary = first_sentence(command->get_description());
    const std::size_t room = kHelpWidth - get_column_width() - 2;
    if (summary.size() > room) {
      summary = summary.substr(0, summary.rfind(' ', room - 4)) + " ...";
    }
    std::string name = "  " + command->get_display_name();
    name.resize(std::max(name.size() + 1, get_column_width()), ' ');
    return name + summary + "\n";
  }
  std::string make_description(const CLI::App* app) const override {
    const std::string& description = app->get_description();
    return description.empty() ? std::string() : wrap(description, kHelpWidth);
  }
  std::string make_option_desc(const CLI::Option* option) const override {
    std::string text =
        wrap(CLI::Formatter::make_option_desc(option), kHelpWidth - get_column_width());
    text.pop_back();  // format_help adds the final newline
    return text;
  }
};

// Exit codes 2-4 mean the same for every command; 0 and 1 are each command's own.
constexpr const char* kCommonExitCodes =
    "  2 usage error\n"
    "  3 bad input data (the message names file, scene, image and field)\n"
    "  4 rendering or runtime failure";

// What exit codes 0 and 1 mean for `command` ("bench visibility" for a benchmark), one per line.
std::string own_exit_codes(const std::string& command) {
  const std::string failed_images =
      "  0 ok\n  1 some images failed under --keep-going (listed in summary.json)\n";
  static const std::map<std::string, std::string> codes = {
      {"", "  0 ok\n  1 as the command's --help says\n"},
      {"visibility", failed_images},
      {"estimate", failed_images},
      {"evaluate", failed_images},
      {"report", failed_images},
      {"merge",
       "  0 ok\n  1 the merged job holds images that failed under --keep-going (listed in "
       "summary.json)\n"},
      {"sensor-fit",
       "  0 every statistic of the preset agrees within --tolerance\n"
       "  1 some statistic is off by more than --tolerance (marked in the table)\n"}};
  const auto found = codes.find(command);
  return found == codes.end() ? "  0 ok\n" : found->second;
}

std::string exit_codes_footer(const std::string& command) {
  return "Exit codes:\n" + own_exit_codes(command) + kCommonExitCodes;
}

// Each command's --help ends with its own exit codes.
void describe_exit_codes(CLI::App& app, const std::string& prefix) {
  for (CLI::App* command : app.get_subcommands({})) {
    const std::string name = prefix + command->get_name();
    command->footer(exit_codes_footer(name));
    describe_exit_codes(*command, name + " ");
  }
}

void describe_app(CLI::App& app) {
  app.formatter(std::make_shared<HelpFormatter>());
  app.description(
      "clutterscope: visibility and pose-belief analysis of cluttered scenes (BOP datasets).\n"
      "Run `clutterscope COMMAND --help` for a command's options.");
  app.set_version_flag("--version", batch::version_text());
  app.require_subcommand(1);
  app.footer(exit_codes_footer(""));
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

CLI::App& bench_command_group(CLI::App& app) {
  for (CLI::App* command : app.get_subcommands({})) {
    if (command->get_name() == "bench") return *command;
  }
  CLI::App* bench =
      app.add_subcommand("bench", "Benchmarks that print timings measured in one run");
  bench->require_subcommand(1);
  return *bench;
}

namespace {

// The command that ran (the leaf: `bench visibility`'s visibility), nullptr before parsing.
const CLI::App* command_run(const CLI::App& app) {
  const auto parsed = app.get_subcommands();
  if (parsed.empty()) return nullptr;
  const CLI::App* deeper = command_run(*parsed.front());
  return deeper != nullptr ? deeper : parsed.front();
}

// Every command that rendered says with what on stderr, unless -q: results differ between
// rasterisers (llvmpipe, a GPU driver). run.json of the batch commands and report records it.
void print_renderer(const CLI::App& app) {
  const std::string renderer = render::renderer_in_use();
  const CLI::App* command = command_run(app);
  if (renderer.empty() || command == nullptr) return;
  const CLI::Option* quiet = command->get_option_no_throw("--quiet");
  if (quiet != nullptr && quiet->count() > 0) return;
  std::cerr << command->get_name() << ": GL renderer " << renderer << "\n";
}

// The first word that names no command where one is expected ("frobnicate", "bench nope"):
// CLI11 would only say "A subcommand is required". Empty when the words name commands.
std::string unknown_command_message(const CLI::App& app, int argc, char** argv) {
  const CLI::App* group = &app;
  std::string path = "clutterscope";
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    const std::vector<const CLI::App*> commands = group->get_subcommands({});
    if (commands.empty() || word.empty() || word[0] == '-') return "";
    const auto found = std::find_if(commands.begin(), commands.end(), [&](const CLI::App* command) {
      return command->check_name(word);
    });
    if (found == commands.end()) {
      std::string message = "unknown command '" + word + "' for " + path + "; the commands are:";
      for (const CLI::App* command : commands) message += " " + command->get_name();
      return message + " (`" + path + " --help` describes them)";
    }
    group = *found;
    path += " " + word;
  }
  return "";
}

}  // namespace

int run_cli(int argc, char** argv) {
  CLI::App app;
  describe_app(app);
  int exit_code = 0;
  add_commands(app, &exit_code);
  describe_exit_codes(app, "");

  // On every way out: a run that failed may have rendered too.
  struct PrintRenderer {
    const CLI::App& app;
    ~PrintRenderer() { print_renderer(app); }
  } print_renderer_on_exit{app};
  const std::string unknown = unknown_command_message(app, argc, argv);
  if (!unknown.empty()) {
    std::cerr << "error: " << unknown << "\n";
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int code = app.exit(error);
    return code == 0 ? 0 : kExitUsage;
  } catch (const batch::UsageError& error) {
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

}  // namespace clutterscope::cli
