#include <algorithm>
#include <cctype>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/report/beliefs.hpp>
#include <cmath>
#include <cstdio>

#include "csv.hpp"

namespace clutterscope::report {

namespace {

std::string percent(double fraction) { return batch::printf_fixed(100.0 * fraction, 1) + "%"; }

std::string image_id(const ImageSummary& image) {
  return image.split + " scene " + std::to_string(image.scene_id) + " image " +
         std::to_string(image.im_id);
}

std::string list_text(const std::vector<int>& values) {
  std::string text;
  for (size_t i = 0; i < values.size(); ++i) {
    if (i > 0) text += i + 1 == values.size() ? " and " : ", ";
    text += std::to_string(values[i]);
  }
  return text;
}

}  // namespace

std::vector<BeliefSampleRow> read_beliefs_csv(const std::filesystem::path& path) {
  const CsvTable table = CsvTable::read(path, batch::belief_samples_table().required_columns());
  std::vector<BeliefSampleRow> rows;
  rows.reserve(table.records().size());
  for (const CsvRecord& record : table.records()) {
    BeliefSampleRow row;
    row.gt_id = table.integer(record, "gt_id");
    row.obj_id = table.integer(record, "obj_id");
    row.iteration = table.integer(record, "iteration");
    if (row.iteration < 1) table.fail(record, "iteration", "must be >= 1");
    row.position_m =
        1e-3 * Eigen::Vector3d(table.number(record, "x_mm"), table.number(record, "y_mm"),
                               table.number(record, "z_mm"));
    row.weight = table.non_negative(record, "weight");
    rows.push_back(row);
  }
  return rows;
}

std::vector<ImageSummary> choose_belief_images(const std::vector<ImageSummary>& images, int count) {
  std::vector<const ImageSummary*> order;
  for (const ImageSummary& image : images) {
    if (image.n_estimated > 0 && image.scene_visibility) order.push_back(&image);
  }
  std::stable_sort(order.begin(), order.end(), [](const auto* a, const auto* b) {
    return *a->scene_visibility < *b->scene_visibility;
  });
  std::vector<ImageSummary> chosen;
  if (order.empty() || count <= 0) return chosen;
  std::vector<size_t> picked;
  for (int j = 0; j < count; ++j) {
    const size_t index =
        count == 1 ? 0
                   : static_cast<size_t>(
                         std::lround(static_cast<double>(j) * (order.size() - 1) / (count - 1)));
    if (std::find(picked.begin(), picked.end(), index) == picked.end()) picked.push_back(index);
  }
  for (size_t index : picked) chosen.push_back(*order[index]);
  return chosen;
}

std::vector<int> shown_iterations(int last) {
  std::vector<int> iterations;
  for (int iteration : {1, (last + 1) / 2, last}) {
    if (iteration >= 1 && iteration <= last &&
        (iterations.empty() || iteration > iterations.back())) {
      iterations.push_back(iteration);
    }
  }
  return iterations;
}

std::string belief_plot_name(const ImageSummary& image) {
  std::string name = "beliefs_" + image.split + "_" + std::to_string(image.scene_id) + "_" +
                     std::to_string(image.im_id);
  for (char& ch : name) {
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-') ch = '_';
    ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  }
  return name;
}

NamedPlot belief_plot(const BeliefImage& figure, double variance_threshold_cm2) {
  int last = 0;
  for (const BeliefSampleRow& sample : figure.samples) last = std::max(last, sample.iteration);
  const std::vector<int> iterations = shown_iterations(last);
  const auto pixel = [&figure](const Eigen::Vector3d& point) {
    const std::vector<std::array<double, 2>> projected = svg::project_to_pixels(figure.K, {point});
    return projected.empty() ? std::optional<std::array<double, 2>>()
                             : std::optional<std::array<double, 2>>(projected.front());
  };

  std::vector<svg::ImagePanel> panels;
  for (int iteration : iterations) {
    svg::ImagePanel panel;
    panel.title = iteration == last
                      ? "beliefs after iteration " + std::to_string(iteration) + " (last)"
                      : "beliefs after iteration " + std::to_string(iteration);
    panels.push_back(panel);
  }
  svg::ImagePanel final_panel;
  final_panel.title = "final estimates (ICP, fused)";
  int drawn = 0, confident = 0;
  for (size_t i = 0; i < figure.objects.size(); ++i) {
    const ObjectRow& object = figure.objects[i];
    std::vector<std::vector<Eigen::Vector3d>> per_panel(iterations.size());
    bool has_samples = false;
    for (const BeliefSampleRow& sample : figure.samples) {
      if (sample.gt_id != object.gt_id) continue;
      const auto at = std::find(iterations.begin(), iterations.end(), sample.iteration);
      if (at == iterations.end()) continue;
      per_panel[static_cast<size_t>(at - iterations.begin())].push_back(sample.position_m);
      has_samples = true;
    }
    if (!object.estimate && !has_samples) continue;  // fixed supports, failed estimates
    ++drawn;
    svg::ProjectedObject projected;
    projected.label = object.label + " (gt " + std::to_string(object.gt_id) + ")";
    projected.colour = svg::category_colour(static_cast<int>(i));
    projected.tag = std::to_string(object.gt_id);  // as in the legend: stacked objects told apart
    for (size_t p = 0; p < iterations.size(); ++p) {
      svg::ProjectedObject samples = projected;
      samples.points = svg::project_to_pixels(figure.K, per_panel[p]);
      panels[p].objects.push_back(std::move(samples));
    }
    const auto truth = figure.ground_truth_m.find(object.gt_id);
    if (truth != figure.ground_truth_m.end()) projected.ground_truth = pixel(truth->second);
    if (object.estimate) {
      const PoseEstimate& estimate = *object.estimate;
      projected.estimate =
          pixel(1e-3 * Eigen::Vector3d(estimate.x_mm, estimate.y_mm, estimate.z_mm));
      projected.estimate_confident = estimate.confident_at(variance_threshold_cm2);
      confident += projected.estimate_confident;
    }
    final_panel.objects.push_back(std::move(projected));
  }
  panels.push_back(std::move(final_panel));

  const ImageSummary& image = figure.image;
  NamedPlot plot;
  plot.name = belief_plot_name(image);
  const std::string threshold = batch::printf_general(variance_threshold_cm2);
  plot.caption = "Belief samples of the " + batch::count_text(drawn, "estimated object") + " of " +
                 image_id(image) + " (scene visibility " +
                 (image.scene_visibility ? percent(*image.scene_visibility) : "undefined") +
                 ") projected on its " + figure.background_kind +
                 (iterations.empty()
                      ? std::string(" (no belief samples)")
                      : " after NBP iteration" + std::string(iterations.size() > 1 ? "s " : " ") +
                            list_text(iterations)) +
                 " (the paper's Fig. 2 d\u2013e), and the final estimates after ICP and fusion "
                 "(Fig. 2 f, Fig. 3): ringed cross confident (max-axis variance \u2264 " +
                 threshold + " cm\u00b2, " + std::to_string(confident) + " of " +
                 std::to_string(drawn) +
                 "), dashed ring not confident, diamond the ground-truth object centre; the "
                 "number beside a marker is the object's gt id.";
  // Two panels a row, each wide enough to tell stacked objects apart (480 px for a 640 px
  // image: the page is 1100 px wide, so the figure is drawn at full size).
  plot.svg = svg::image_panels("Beliefs and estimates in " + image_id(image), figure.background,
                               panels, svg::PanelLayout{480, 2, false});
  return plot;
}

}  // namespace clutterscope::report
