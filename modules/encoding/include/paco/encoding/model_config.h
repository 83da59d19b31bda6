#pragma once
// Usage:
//   paco::ModelConfig config = paco::ModelConfig::preset("cpu");   // or "paper"
//   config.decoder_depth = 6; config.validate();                    // throws InvalidInputError
//   std::string text = config.toJson(); auto same = paco::ModelConfig::fromJson(text);
#include <string>
#include <vector>

namespace paco {

/// Every size of the PaCo network (plane proxy encoder + parametric completer). Plain data: no
/// LibTorch here. The defaults are the `paper` preset (about 41 M parameters). All lengths are in
/// the normalised frame (centre at the origin, unit bounding-box diagonal).
struct ModelConfig {
  std::string name = "paper";  ///< preset name this config started from (informative only)

  // --- point proxies (PoinTr-style) ---
  int num_centres = 128;  ///< FPS centres = point proxies per cloud (>= 1)
  int knn_k = 16;         ///< points per kNN group around each centre (>= 1)
  int input_embedding = 8;  ///< width of the per-point embedding before the edge convs (>= 1)
  /// Output widths of the edge-conv stack; each layer sees [f_j - f_centre, f_centre] (2x input).
  std::vector<int> edge_conv_widths{32, 64, 64, 128};
  int group_norm_groups = 4;  ///< GroupNorm groups in the edge convs; must divide every width
  int width = 384;            ///< transformer width C (>= 8, divisible by `heads`)
  int heads = 6;              ///< attention heads (>= 1)
  double mlp_ratio = 2.0;     ///< hidden width of every transformer MLP = mlp_ratio * width (> 0)
  int position_hidden = 128;  ///< hidden width of the centre positional embedding 3 -> h -> C
  int encoder_depth = 8;      ///< transformer blocks over the point proxies (0 allowed)
  int encoder_graph_k = 8;    ///< kNN graph attention over centres in the first block (0: off)
  int normal_hidden = 128;    ///< hidden width of the plane-normal MLP Phi(n)

  // --- plane proxies and query generation ---
  int plane_slots = 20;         ///< K: plane proxy slots; the K largest segments are kept
  int global_width = 1024;      ///< width of the global feature that generates queries
  int generated_queries = 40;   ///< queries generated from the global feature (>= kept_queries)
  int kept_queries = 40;        ///< M: queries kept by the trained ranking (top M scores)

  // --- decoder and heads ---
  int decoder_depth = 12;       ///< decoder blocks (self-attn + cross-attn to plane proxies)
  int points_per_plane = 1280;  ///< P: points the distributor places on every predicted plane
  int distributor_hidden = 1024;  ///< hidden width of the point-distributor MLP
  /// "projected" (default: raw 3-D points orthogonally projected onto the predicted plane) or
  /// "polar" (the paper's ray formula r_ij = h / (u_ij . n), from an origin shifted to distance
  /// h = 1 from the plane, denominator clamped away from 0, then projected).
  std::string distributor = "projected";
  /// How the input is turned before the network sees it (after centring and scaling by its own
  /// bounding box): "as-is" (not turned) or "seen-planes" (its dominant seen faces onto the
  /// coordinate axes, paco::seenPlanesRotation; the box is then taken in the turned axes).
  /// Training must use the same (paco_train --input-orientation); stored with the model.
  std::string input_orientation = "as-is";

  /// The named presets: "paper" (reference sizes, ~41 M parameters) and "cpu" (small, chosen by
  /// measurement for 2 CPU cores; see doc/benchmarks.md). Throws InvalidInputError otherwise.
  static ModelConfig preset(const std::string& name);
  /// Names accepted by preset().
  static std::vector<std::string> presetNames();

  /// Throws InvalidInputError naming the first bad field and its allowed range.
  void validate() const;

  /// One flat JSON object (every field); fromJson() reads it back (unknown keys are an error,
  /// missing keys keep the defaults). Throws InvalidInputError on malformed text.
  std::string toJson() const;
  static ModelConfig fromJson(const std::string& json);

  /// Field-by-field equality (including `name`).
  bool operator==(const ModelConfig& other) const;
  bool operator!=(const ModelConfig& other) const { return !(*this == other); }
  /// The first differing field as "field: a vs b" (empty when equal, ignores `name`).
  std::string firstDifference(const ModelConfig& other) const;
};

}  // namespace paco
