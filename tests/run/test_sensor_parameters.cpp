// Sensor models' parameter files: paper 000 §8.2's block exactly as printed there, YAML,
// and every error naming the file, the line and the key.
#include <gtest/gtest.h>

#include "run/sensor_parameters.hpp"

namespace rilbed::run {
namespace {

// The model's declared keys: those of paper 000's track sensor.
agents::SensorModelEntry track_model() {
  agents::SensorModelEntry e;
  e.name = "track_element";
  e.params = {{"Height", "mm", "", 8.0, false, 1e-3, 1e3},
              {"Inclination", "deg", "", 45.0, false, 0, 89},
              {"Cone Angle", "deg", "", 30.0, false, 1e-3, 178},
              {"Precision", "", "", 16.0, true, 1, 4096},
              {"Coverage", "%", "", 15.0, false, 0, 100},
              {"Max Value", "", "", 255.0, true, 1, 1e6},
              {"Error Level", "%", "", std::nullopt, false, 0, 1000}};
  return e;
}

// Paper 000 §8.2, as printed (blank lines between the keys, spaces before `=`).
const char* kPaperBlock =
    "Sensor = {  \n  \n    Height      = 8  \n  \n    Inclination = 45  \n  \n    Cone Angle  = 30  \n  \n"
    "    Precision   = 16  \n  \n    Coverage    = 15  \n  \n    Max Value   = 255  \n  \n    Error Level = 5  \n  "
    "\n}\n";

std::string error_of(const std::string& text) {
  const auto file = parse_parameter_text(text, "p.txt");
  if (!file) return file.error();
  const auto values = parameter_values(track_model(), *file);
  return values ? std::string("accepted") : values.error();
}

TEST(SensorParameters, PaperFormatAsPrinted) {
  const auto file = parse_parameter_text(kPaperBlock, "p.txt");
  ASSERT_TRUE(file) << file.error();
  ASSERT_EQ(file->entries.size(), 7u);
  EXPECT_EQ(file->entries[2].key, "Cone Angle");
  EXPECT_EQ(file->entries[2].value, 30.0);
  EXPECT_EQ(file->entries[2].line, 7);
  const auto values = parameter_values(track_model(), *file);
  ASSERT_TRUE(values) << values.error();
  EXPECT_EQ(*values, (std::vector<double>{8, 45, 30, 16, 15, 255, 5}));
}

TEST(SensorParameters, YamlFlatOrUnderOneNameWithDefaultsBehind) {
  const auto flat = parse_parameter_text("# an element\ncone_angle: 20\nerror level: 2.5\n", "p.yaml");
  ASSERT_TRUE(flat) << flat.error();
  const auto values = parameter_values(track_model(), *flat);
  ASSERT_TRUE(values) << values.error();
  EXPECT_EQ(*values, (std::vector<double>{8, 45, 20, 16, 15, 255, 2.5}));
  const auto nested = parse_parameter_text("Sensor:\n  Height: 12\n  Error Level: 0\n", "p.yaml");
  ASSERT_TRUE(nested) << nested.error();
  EXPECT_EQ(nested->entries[0].line, 2);
  EXPECT_EQ(parameter_values(track_model(), *nested)->at(0), 12.0);
}

TEST(SensorParameters, EveryErrorNamesTheFileTheLineAndTheKey) {
  EXPECT_EQ(error_of("Sensor = {\n  Height = 8\n  Colour = 3\n}\n"),
            "p.txt:3: Colour: the sensor model track_element has no such parameter (it takes Height, Inclination, "
            "Cone Angle, Precision, Coverage, Max Value, Error Level)");
  EXPECT_EQ(error_of("Sensor = {\n  Height = 8\n}\n"),
            "p.txt: Error Level: missing: the sensor model track_element needs it");
  EXPECT_EQ(error_of("Sensor = {\n  Precision = 16.5\n  Error Level = 5\n}\n"),
            "p.txt:2: Precision: must be a whole number");
  EXPECT_EQ(error_of("Sensor = {\n  Error Level = 5\n  Coverage = 150\n}\n"),
            "p.txt:3: Coverage: must be 0 to 100 (%), not 150");
  EXPECT_EQ(error_of("Sensor = {\n  Height = tall\n}\n"), "p.txt:2: Height: 'tall' is not a finite number");
  EXPECT_EQ(error_of("Sensor = {\n  Height = nan\n}\n"), "p.txt:2: Height: 'nan' is not a finite number");
  EXPECT_EQ(error_of("Sensor = {\n  Height = 8\n  height = 9\n}\n"), "p.txt:3: height: given twice");
  EXPECT_EQ(error_of("Sensor = {\n  Height = 8\n"), "p.txt: no closing }");
  EXPECT_EQ(error_of("Sensor = {\n}\nHeight = 8\n"), "p.txt:3: text after the closing }");
  EXPECT_EQ(error_of("Sensor = {\n  Height 8\n}\n"), "p.txt:2: expected `Key = number` or `}`");
  EXPECT_EQ(error_of("height: [8]\n"), "p.txt:1: height: must be a number");
  EXPECT_EQ(error_of("height: 8\nHeight: 9\n"), "p.txt:2: Height: given twice");
  EXPECT_NE(error_of("height: {8\n").find("p.txt:"), std::string::npos);
  EXPECT_EQ(error_of("- 8\n"), "p.txt: expected a mapping of keys to numbers (or paper 000's format)");
  EXPECT_EQ(error_of("Sensor = {  # the element\n  Error Level = 5  # per cent\n}\n"), "accepted");
}

TEST(SensorParameters, AFileThatIsNotThereIsNamed) {
  const auto file = read_parameter_file("/nonexistent/element.txt");
  ASSERT_FALSE(file);
  EXPECT_EQ(file.error(), "/nonexistent/element.txt: cannot open the parameter file");
}

}  // namespace
}  // namespace rilbed::run
