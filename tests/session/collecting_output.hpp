#pragma once
// A StageOutput for tests that call a stage or tracker directly: keeps every result, each warning
// as "CODE field: message", and the calibration report.
#include <string>
#include <vector>

#include "session/pipeline_stage.hpp"

namespace posefuse::session::testing {

struct CollectingOutput : StageOutput {
  void emit(v1::FitResult&& result) override { results.push_back(std::move(result)); }
  void warn(const std::string& code, const std::string& field, const std::string& message) override {
    warnings.push_back(code + " " + field + ": " + message);
  }
  v1::CalibrationReport& calibration() override { return report; }
  std::vector<v1::FitResult> results;
  std::vector<std::string> warnings;
  v1::CalibrationReport report;
};

}  // namespace posefuse::session::testing
