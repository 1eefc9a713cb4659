#pragma once

// The BOP 2019 scores from per-estimate pose errors, as bop_toolkit computes them
// (scripts/eval_calc_errors.py chooses the estimates, scripts/eval_calc_scores.py,
// pose_matching.match_poses and score.calc_localization_scores match them and count, and
// scripts/eval_bop19_pose.py averages the recalls). Pure functions of ids, scores, visible
// fractions and errors: no files, no geometry.

#include <map>
#include <utility>
#include <vector>

namespace clutterscope::estimator {

// eval_bop19_pose.py's correctness thresholds, the exact doubles of numpy's arange:
// 0.05, 0.1, 0.15000000000000002, ..., 0.5 for MSSD (a fraction of the diameter) and for VSD's
// tau and theta; 5, 10, ..., 50 px for MSPD (at an image width of 640 px).
std::vector<double> bop19_fraction_thresholds();
std::vector<double> bop19_mspd_thresholds_px();

// eval_calc_errors.py's choice for one target: the estimates of one (image, object), given by
// their scores in file order, sorted by decreasing score (a stable sort: equal scores keep the
// file order), the first n_top of them (all when n_top <= 0). Returns their indices in file
// order (bop_toolkit's est_id), best first.
std::vector<int> bop_top_estimates(const std::vector<double>& scores_in_file_order, int n_top);

// One GT instance of an image (scene_gt.json order): its object and bop19 visib_fract
// (scene_gt_info.json).
struct BopGtInstance {
  int obj_id = 0;
  double visib_fract = 0.0;
};

// Which GT instances of an image count (eval_calc_scores.py's scene_gt_valid). `targets` maps
// the image's target objects to their inst_count. With visib_gt_min < 0 (BOP 2019: -1), per
// target object its inst_count instances with the highest visib_fract (ties: lower index
// first); otherwise the instances of target objects with visib_fract >= visib_gt_min.
// Instances of other objects never count.
std::vector<bool> bop_valid_gt(const std::vector<BopGtInstance>& gt,
                               const std::map<int, int>& targets, double visib_gt_min);

// One evaluated estimate of an object in an image, with its errors against the GT instances
// of the same object, (gt index, error) by increasing gt index. The errors are normalised as
// the threshold is: MSSD divided by the diameter, MSPD multiplied by 640 / image width; an
// infinite error (MSSD's shortcut) never matches.
struct BopEstimateErrors {
  int est_id = 0;
  double score = 0.0;
  std::vector<std::pair<int, double>> errors;
};

// pose_matching.match_poses for one object of one image: estimates by decreasing score (stable)
// each take the valid, still unmatched GT instance with the lowest error strictly below
// `threshold` (ties: the lower index). Returns, per GT instance of the image (`gt_count`), the
// est_id matched to it, or -1.
std::vector<int> bop_match(const std::vector<BopEstimateErrors>& estimates,
                           const std::vector<bool>& valid, double threshold, int gt_count);

// One target image: its GT instances, its target objects (obj_id -> inst_count) and the
// evaluated estimates per object (obj_id -> estimates, as bop_top_estimates chose them).
struct BopImageErrors {
  int scene_id = 0;
  int im_id = 0;
  std::vector<BopGtInstance> gt;
  std::map<int, int> targets;
  std::map<int, std::vector<BopEstimateErrors>> estimates;
};

// score.calc_localization_scores with n_top = -1 for one threshold: targets_count counts the
// valid GT instances, tp_count those matched, gt_count every GT instance of the images;
// recall = tp_count / targets_count (0 without targets).
struct BopRecall {
  double threshold = 0.0;
  int tp_count = 0;
  int targets_count = 0;
  int gt_count = 0;
  double recall = 0.0;
};
BopRecall bop_recall(const std::vector<BopImageErrors>& images, double threshold,
                     double visib_gt_min = -1.0);

// numpy.mean as bop_toolkit averages (pairwise summation, so the last bit agrees); 0 for none.
double bop_mean(const std::vector<double>& values);

// The BOP 2019 average recall of one error type: the plain mean of its recalls (10 for MSSD
// and MSPD, 100 for VSD); bop19_average_recall is bop_mean of the three.
double bop_average_recall(const std::vector<BopRecall>& recalls);

}  // namespace clutterscope::estimator
