#include <unistd.h>

#include <atomic>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/files.hpp>

namespace clutterscope::batch {

namespace fs = std::filesystem;

void write_output_file(const fs::path& out_dir, const fs::path& relative,
                       const std::string& bytes) {
  static std::atomic<unsigned long> counter{0};
  const fs::path temporary_dir = out_dir / ".batch" / "tmp";
  const fs::path temporary =
      temporary_dir / (std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".tmp");
  datasets::write_file_atomically(temporary, bytes);  // creates temporary_dir
  const fs::path target = out_dir / relative;
  datasets::create_folders(target.parent_path());
  datasets::rename_checked(temporary, target);
}

}  // namespace clutterscope::batch
