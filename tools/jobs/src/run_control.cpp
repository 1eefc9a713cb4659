#include <clutterscope/jobs/run_control.hpp>
#include <stdexcept>
#include <utility>

namespace clutterscope::jobs {

batch::BatchOptions RunControl::apply(batch::BatchOptions batch, const std::string& step) const {
  if (progress) {
    batch.on_progress = [callback = progress, step](std::size_t done, std::size_t total) {
      callback(Progress{step, done, total});
    };
  }
  batch.cancel = cancel.flag();
  batch.keep_results = keep_results;
  return batch;
}

const Table& JobSummary::table(const std::string& file_name) const {
  for (const Table& table : tables) {
    if (table.file_name == file_name) return table;
  }
  throw std::out_of_range(command + ": no table " + file_name + " in memory (" +
                          (tables.empty() ? "none kept: keep_results off or the run incomplete"
                                          : "the job writes other tables") +
                          ")");
}

JobSummary job_summary(const batch::BatchOutputSpec& output, const std::filesystem::path& out,
                       batch::BatchResult run) {
  JobSummary summary;
  summary.command = output.command;
  summary.out = out;
  for (std::size_t t = 0; t < run.tables.size() && t < output.tables.size(); ++t) {
    Table table;
    table.file_name = output.tables[t].file_name;
    const std::string& header = output.tables[t].header;
    for (std::size_t start = 0;;) {
      const std::size_t comma = header.find(',', start);
      table.columns.push_back(header.substr(start, comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    table.text = std::move(run.tables[t]);
    summary.tables.push_back(std::move(table));
  }
  run.tables.clear();
  summary.summary = std::move(run.summary);
  run.summary = nullptr;
  summary.run = std::move(run);
  return summary;
}

}  // namespace clutterscope::jobs
