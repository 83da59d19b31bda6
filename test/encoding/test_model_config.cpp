#include <paco/common/error.h>
#include <paco/encoding/model_config.h>

#include <gtest/gtest.h>

namespace paco {
namespace {

TEST(ModelConfig, PresetsAreValidAndDifferent) {
  for (const auto& name : ModelConfig::presetNames()) {
    const ModelConfig config = ModelConfig::preset(name);
    EXPECT_EQ(config.name, name);
    EXPECT_NO_THROW(config.validate()) << name;
  }
  const auto paper = ModelConfig::preset("paper"), cpu = ModelConfig::preset("cpu");
  EXPECT_EQ(paper.width, 384);
  EXPECT_EQ(paper.encoder_depth, 8);
  EXPECT_EQ(paper.decoder_depth, 12);
  EXPECT_EQ(paper.plane_slots, 20);
  EXPECT_EQ(paper.kept_queries, 40);
  EXPECT_EQ(paper.num_centres, 128);
  EXPECT_LT(cpu.width * cpu.decoder_depth, paper.width * paper.decoder_depth);
  EXPECT_THROW(ModelConfig::preset("huge"), InvalidInputError);
}

TEST(ModelConfig, JsonRoundTripKeepsEveryField) {
  ModelConfig config = ModelConfig::preset("cpu");
  config.edge_conv_widths = {8, 12};
  config.mlp_ratio = 1.75;
  config.distributor = "polar";
  config.encoder_depth = 0;
  config.input_orientation = "seen-planes";
  const ModelConfig back = ModelConfig::fromJson(config.toJson());
  EXPECT_EQ(back, config);
  EXPECT_EQ(back.edge_conv_widths, (std::vector<int>{8, 12}));
  EXPECT_DOUBLE_EQ(back.mlp_ratio, 1.75);
  EXPECT_EQ(back.distributor, "polar");
  EXPECT_EQ(back.input_orientation, "seen-planes");
  // Model files written before the field existed read as "as-is" (missing keys keep defaults).
  EXPECT_EQ(ModelConfig::fromJson("{\"width\": 384}").input_orientation, "as-is");
}

TEST(ModelConfig, JsonErrorsAreReported) {
  EXPECT_THROW(ModelConfig::fromJson("not json"), InvalidInputError);
  EXPECT_THROW(ModelConfig::fromJson("{\"no_such_field\": 3}"), InvalidInputError);
  EXPECT_THROW(ModelConfig::fromJson("{\"width\": \"wide\"}"), InvalidInputError);
  EXPECT_THROW(ModelConfig::fromJson("{\"edge_conv_widths\": [8, x]}"), InvalidInputError);
  // Missing keys keep the defaults.
  EXPECT_EQ(ModelConfig::fromJson("{\"width\": 96}").width, 96);
  EXPECT_EQ(ModelConfig::fromJson("{\"width\": 96}").decoder_depth, ModelConfig().decoder_depth);
}

TEST(ModelConfig, ValidateNamesTheBadField) {
  auto expectBad = [](ModelConfig c, const std::string& field) {
    try {
      c.validate();
      ADD_FAILURE() << "no error for " << field;
    } catch (const InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  ModelConfig c = ModelConfig::preset("cpu");
  c.width = 100;  // not divisible by 6 heads
  expectBad(c, "width");
  c = ModelConfig::preset("cpu");
  c.generated_queries = c.kept_queries - 1;
  expectBad(c, "generated_queries");
  c = ModelConfig::preset("cpu");
  c.distributor = "spherical";
  expectBad(c, "distributor");
  c = ModelConfig::preset("cpu");
  c.input_orientation = "upright";
  expectBad(c, "input_orientation");
  c = ModelConfig::preset("cpu");
  c.edge_conv_widths = {30};  // not divisible by 4 groups
  expectBad(c, "edge_conv_widths");
  c = ModelConfig::preset("cpu");
  c.plane_slots = 0;
  expectBad(c, "plane_slots");
}

TEST(ModelConfig, FirstDifferenceNamesTheField) {
  ModelConfig a = ModelConfig::preset("cpu"), b = a;
  EXPECT_EQ(a.firstDifference(b), "");
  b.decoder_depth += 1;
  EXPECT_NE(a.firstDifference(b).find("decoder_depth"), std::string::npos);
  EXPECT_NE(a, b);
}

}  // namespace
}  // namespace paco
