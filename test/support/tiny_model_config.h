#pragma once
// A tiny ModelConfig shared by the encoding and completion tests: a forward pass takes a few
// milliseconds. Header-only; include it from tests that link paco::encoding.
#include <paco/encoding/model_config.h>

#include <string>

namespace paco::test {

/// A model small enough that a forward pass takes a few milliseconds.
inline ModelConfig tinyModelConfig(const std::string& distributor = "projected") {
  ModelConfig c = ModelConfig::preset("cpu");
  c.name = "tiny";
  c.num_centres = 32;
  c.knn_k = 8;
  c.edge_conv_widths = {8, 16};
  c.width = 32;
  c.heads = 4;
  c.position_hidden = 16;
  c.normal_hidden = 16;
  c.encoder_depth = 1;
  c.encoder_graph_k = 4;
  c.plane_slots = 6;
  c.global_width = 64;
  c.generated_queries = 8;
  c.kept_queries = 6;
  c.decoder_depth = 2;
  c.points_per_plane = 16;
  c.distributor_hidden = 32;
  c.distributor = distributor;
  return c;
}

}  // namespace paco::test
