#pragma once

// Executing exported notebooks in tests: Debian's Jupyter (jupyter-nbconvert, python3-nbclient,
// python3-ipykernel, python3-pandas, python3-matplotlib; scripts/install-deps.sh) in a hermetic
// environment, and reading what the executed cells printed.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace clutterscope::testing {

// `text` in single quotes for sh.
std::string shell_quote(const std::string& text);

// Runs a shell command with its output in `log`; returns the exit status (-1 if it died).
int run_logged(const std::string& command, const std::filesystem::path& log);

// The Python that has nbformat: Debian's, which the Jupyter packages are installed for (a
// pyenv or venv python3 earlier on PATH usually lacks them). "" when there is none.
std::string find_python(const std::filesystem::path& scratch);

// `env ...` making everything Jupyter, IPython and matplotlib write or read per user go under
// `home`, so that a test neither depends on nor changes the user's configuration.
std::string hermetic_env(const std::filesystem::path& home);

// The cell with this id; throws std::runtime_error when there is none.
const nlohmann::json& cell_by_id(const nlohmann::json& notebook, const std::string& id);

// What a cell printed on `stream` (stdout or stderr).
std::string stream_text(const nlohmann::json& cell, const std::string& stream = "stdout");

}  // namespace clutterscope::testing
