#pragma once

// Two methods whose evaluation is known by construction, as the report's evaluate step would
// give them (analyse_by_visibility over hand-made targets, its by_visibility.json, scores.json
// entries): 14 targets of bop19 visib_fract 0.15 ... 1.0, none below 0.1; the scene visibility
// of each target equals its visib_fract.
//  - "robust": every pose right (MSSD 0.01 diameter), score 0.9: recall 1 in every band.
//  - "fragile": right at visibility >= 0.5 (MSSD 0.01, score 0.9), wrong below (MSSD 0.3, which
//    only the thresholds 0.35 ... 0.5 recall: 4 of 10; score 0.8): recall 0.4 below 0.5, 1
//    above; its error falls as visibility grows (Spearman < 0), and "score >= 0.9" accepts
//    exactly its right poses.
// Header-only.

#include <clutterscope/report/by_visibility.hpp>
#include <clutterscope/report/evaluation.hpp>
#include <vector>

namespace clutterscope::report::testing {

inline const std::vector<double>& evaluation_visibilities() {
  static const std::vector<double> values = {0.15, 0.2,  0.25, 0.35, 0.4,  0.45, 0.55,
                                             0.6,  0.65, 0.75, 0.8,  0.85, 0.95, 1.0};
  return values;
}

inline MethodTargets evaluation_method(const std::string& name, bool fragile) {
  MethodTargets method{name, {}};
  int gt_id = 0;
  for (const double visibility : evaluation_visibilities()) {
    TargetOutcome target;
    target.scene_id = 1;
    target.im_id = gt_id;  // one target per image, so each has its own scene visibility
    target.obj_id = 5;
    target.gt_id = 0;
    target.visib_fract = visibility;
    target.scene_visibility = visibility;
    TargetEstimate estimate;
    const bool right = !fragile || visibility >= 0.5;
    estimate.mssd = right ? 0.01 : 0.3;
    estimate.score = right ? 0.9 : 0.8;
    target.estimate = estimate;
    method.targets.push_back(target);
    ++gt_id;
  }
  return method;
}

// The evaluation of both methods against visib_fract and against the scene visibility.
inline EvaluationResults known_evaluation() {
  const std::vector<MethodTargets> methods = {evaluation_method("robust", false),
                                              evaluation_method("fragile", true)};
  ByVisibilityOptions options;
  options.bootstrap.resamples = 200;
  EvaluationResults evaluation;
  evaluation.methods = {"robust", "fragile"};
  evaluation.by_visib_fract = by_visibility_json(analyse_by_visibility(methods, options));
  options.visibility = VisibilityMeasure::kScene;
  evaluation.by_scene_visibility = by_visibility_json(analyse_by_visibility(methods, options));
  // scores.json as evaluate writes it with MSSD only: (6 * 0.4 + 8 * 1) / 14 for fragile.
  evaluation.scores = {{"robust",
                        {{"bop19_average_recall_mssd", 1.0},
                         {"bop19_average_recall", nullptr},
                         {"bop19_average_time_per_image", 0.5}}},
                       {"fragile",
                        {{"bop19_average_recall_mssd", 10.4 / 14},
                         {"bop19_average_recall", nullptr},
                         {"bop19_average_time_per_image", -1}}}};
  return evaluation;
}

}  // namespace clutterscope::report::testing
