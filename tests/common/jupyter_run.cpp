#include "jupyter_run.hpp"

#include <sys/wait.h>

#include <cstdlib>
#include <stdexcept>
#include <utility>
#include <vector>

namespace clutterscope::testing {

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

int run_logged(const std::string& command, const std::filesystem::path& log) {
  const int status = std::system((command + " > " + shell_quote(log.string()) + " 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string find_python(const std::filesystem::path& scratch) {
  for (const std::string candidate : {"/usr/bin/python3", "python3"}) {
    if (run_logged(candidate + " -c 'import nbformat'", scratch / "probe.log") == 0) {
      return candidate;
    }
  }
  return "";
}

std::string hermetic_env(const std::filesystem::path& home) {
  std::string env = "env -u JUPYTER_PATH -u JUPYTER_CONFIG_PATH -u PYTHONPATH";
  for (const auto& [name, sub] :
       std::vector<std::pair<std::string, std::string>>{{"HOME", ""},
                                                        {"JUPYTER_CONFIG_DIR", "jupyter-config"},
                                                        {"JUPYTER_DATA_DIR", "jupyter-data"},
                                                        {"JUPYTER_RUNTIME_DIR", "jupyter-runtime"},
                                                        {"IPYTHONDIR", "ipython"},
                                                        {"MPLCONFIGDIR", "matplotlib"},
                                                        {"XDG_CACHE_HOME", "cache"}}) {
    env += " " + name + "=" + shell_quote((home / sub).string());
  }
  return env + " MPLBACKEND=Agg PYDEVD_DISABLE_FILE_VALIDATION=1 PYTHONDONTWRITEBYTECODE=1";
}

const nlohmann::json& cell_by_id(const nlohmann::json& notebook, const std::string& id) {
  for (const nlohmann::json& cell : notebook["cells"]) {
    if (cell["id"] == id) return cell;
  }
  throw std::runtime_error("no cell " + id);
}

std::string stream_text(const nlohmann::json& cell, const std::string& stream) {
  std::string text;
  for (const nlohmann::json& output : cell["outputs"]) {
    if (output["output_type"] != "stream" || output["name"] != stream) continue;
    const nlohmann::json& lines = output["text"];
    if (lines.is_string()) {
      text += lines.get<std::string>();
    } else {
      for (const nlohmann::json& line : lines) text += line.get<std::string>();
    }
  }
  return text;
}

}  // namespace clutterscope::testing
