#pragma once
// Small models and synthetic batches for the network, checkpoint and public-API tests.
#include "tiny_model_config.h"
#include <paco/completion/network.h>
#include <paco/encoding/model_config.h>

namespace paco::test {

/// Points on the 6 faces of a box in the normalised frame, labelled by face (`faces` of them
/// labelled, the rest -1), with the face normals. Deterministic for a seed.
inline NetworkInput boxBatch(int64_t batch, int64_t n, int faces = 6, uint64_t seed = 5) {
  torch::manual_seed(seed);
  auto face = torch::randint(0, 6, {batch, n}, torch::kLong);
  auto points = (torch::rand({batch, n, 3}) - 0.5) * 0.5;
  auto normals = torch::zeros({batch, n, 3});
  auto axis = face.remainder(3);
  auto side = torch::where(face >= 3, torch::full({batch, n}, 0.25), torch::full({batch, n}, -0.25));
  for (int a = 0; a < 3; ++a) {
    auto on = axis.eq(a);
    points.select(2, a).copy_(torch::where(on, side, points.select(2, a)));
    normals.select(2, a).copy_(torch::where(on, torch::sign(side), torch::zeros_like(side)));
  }
  auto labels = torch::where(face < faces, face, torch::full_like(face, -1));
  return {points, normals, labels};
}

}  // namespace paco::test
