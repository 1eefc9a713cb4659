// Uses the installed libraries as a user's code would: opens a BOP dataset (datasets), counts
// its test images and evaluates Eq. 10 (visibility).
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/visibility/eq10.hpp>
#include <iostream>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: consumer DATASET\n";
    return 2;
  }
  const auto dataset = clutterscope::datasets::BopDataset::open(argv[1]);
  clutterscope::datasets::DatasetSelection selection;
  selection.splits = {"test"};
  std::cout << "images " << dataset.list_images(selection).size() << "\n";
  std::cout << "object visibility " << clutterscope::visibility::object_visibility(30, 120) << "\n";
  return 0;
}
