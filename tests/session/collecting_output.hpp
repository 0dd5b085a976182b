#pragma once
// A StageOutput for tests that call a stage or tracker directly: keeps every result, each warning
// as "CODE field: message", and the calibration report.
#include <optional>
#include <string>
#include <vector>

#include "session/pipeline_stage.hpp"
#include "session/result_encoder.hpp"

namespace posefuse::session::testing {

struct CollectingOutput : StageOutput {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  // Kept as the value and, as the pipeline sends it to the client, as a FitResult in `results`.
  void hand_on(StageValue&& value) override {
    if (std::optional<v1::FitResult> result = encode_value(value)) results.push_back(std::move(*result));
    values.push_back(std::move(value));
  }
  void warn(const std::string& code, const std::string& field, const std::string& message) override {
    warnings.push_back(code + " " + field + ": " + message);
  }
  v1::CalibrationReport& calibration() override { return report; }
  std::vector<v1::FitResult> results;
  std::vector<StageValue> values;
  std::vector<std::string> warnings;
  v1::CalibrationReport report;
};

}  // namespace posefuse::session::testing
