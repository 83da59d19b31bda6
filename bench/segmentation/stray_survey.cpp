// How many inputs of a paco_dataset split have stray points (paco::findStrayPoints), which the
// tools and paco_eval leave out before segmentation (doc/results.md, twenty-sixth session).
// Usage: paco_stray_survey DATASET_DIR SPLIT      (SPLIT: train|val|test; every level and view)
#include <paco/common/error.h>
#include <paco/data/dataset.h>
#include <paco/segmentation/thinning.h>

#include <cstdio>
#include <exception>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s DATASET_DIR SPLIT\n", argv[0]);
    return 2;
  }
  try {
    const paco::data::Dataset dataset(argv[1]);
    const paco::data::Split split = paco::data::splitFromString(argv[2]);
    const std::size_t inputs = dataset.size(split);
    std::size_t with_strays = 0, stray_points = 0;
    for (std::size_t i = 0; i < inputs; ++i) {
      const std::size_t found = paco::findStrayPoints(dataset.load(split, i).input).size();
      with_strays += found > 0 ? 1 : 0;
      stray_points += found;
    }
    std::printf("%zu inputs, %zu with stray points (%zu points in all)\n", inputs, with_strays, stray_points);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
