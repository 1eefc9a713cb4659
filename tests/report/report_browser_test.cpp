#include <gtest/gtest.h>

#include <clutterscope/report/beliefs.hpp>
#include <clutterscope/report/evaluation.hpp>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/svg.hpp>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "report_evaluation_fixture.hpp"
#include "report_test_tables.hpp"
#include "requirements.hpp"

// report.html in a real browser: headless Chromium (Debian `chromium`, installed by
// scripts/install-deps.sh) loads the file from disk; the test saves a screenshot, checks that
// the page logged no console message and no failed load, and that every plot has a non-zero
// rendered size.

namespace clutterscope::report {
namespace {

const char* kChromium = "/usr/bin/chromium";

std::string chromium_command(const std::filesystem::path& profile, const std::string& arguments,
                             const std::filesystem::path& stdout_file,
                             const std::filesystem::path& stderr_file) {
  return std::string("timeout 120 ") + kChromium +
         " --headless --no-sandbox --disable-gpu --disable-background-networking"
         " --disable-component-update --disable-sync --no-first-run --user-data-dir='" +
         profile.string() + "' --enable-logging=stderr --v=0 " + arguments + " > '" +
         stdout_file.string() + "' 2> '" + stderr_file.string() + "'";
}

// Lines Chromium logs for page console messages, uncaught exceptions and failed loads.
std::vector<std::string> page_errors(const std::string& log) {
  std::vector<std::string> errors;
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    for (const char* marker : {":CONSOLE", "Uncaught", "Failed to load", "net::ERR_"}) {
      if (line.find(marker) != std::string::npos) {
        errors.push_back(line);
        break;
      }
    }
  }
  return errors;
}

TEST(ReportBrowser, ChromiumLoadsReportWithoutErrorsAndEveryPlotHasASize) {
  if (!std::filesystem::exists(kChromium)) {
    CLUTTERSCOPE_SKIP_OR_FAIL("CHROMIUM") << kChromium << " is missing: install Debian's chromium "
                                          << "(scripts/install-deps.sh) to run the browser test";
  }
  const std::filesystem::path dir = testing::fresh_dir("browser");
  const auto rows = testing::synthetic_dataset(12);
  ReportOptions options;
  options.bootstrap.resamples = 300;
  const ReportAnalysis analysis = analyse_report(rows, {}, options);
  std::vector<NamedPlot> plots = standard_plots(rows, analysis);
  // Two belief figures as the report command adds (paper Fig. 2 d-f, Fig. 3): samples over
  // an image beside the final estimates, one image per figure.
  for (int im = 0; im < 2; ++im) {
    BeliefImage figure;
    figure.image = analysis.images[static_cast<size_t>(im)];
    cv::Mat raster(120, 160, CV_8UC3, cv::Scalar(200, 200, 200));
    cv::rectangle(raster, {40, 30}, {100, 90}, cv::Scalar(60, 90, 160), cv::FILLED);
    figure.background = svg::BackgroundImage::from_raster(raster);
    figure.background_kind = "RGB image";
    figure.K << 100, 0, 80, 0, 100, 60, 0, 0, 1;
    for (const ObjectRow& row : rows) {
      if (row.im_id != figure.image.im_id) continue;
      figure.objects.push_back(row);
      if (!row.estimate) continue;
      const Eigen::Vector3d centre =
          1e-3 * Eigen::Vector3d(row.estimate->x_mm, row.estimate->y_mm, row.estimate->z_mm);
      figure.ground_truth_m[row.gt_id] = centre + Eigen::Vector3d(0.005, 0.0, 0.0);
      for (int iteration = 1; iteration <= 15; ++iteration) {
        for (int s = 0; s < 20; ++s) {
          const double spread = 0.002 * (16 - iteration) * (s % 5 - 2);
          figure.samples.push_back({row.gt_id, row.obj_id, iteration,
                                    centre + Eigen::Vector3d(spread, 0.001 * (s / 5), 0.0), 0.05});
        }
      }
    }
    plots.push_back(belief_plot(figure, options.variance_threshold_cm2));
  }
  // The pose evaluation of report --results: two methods against both visibility measures.
  const EvaluationResults evaluation = testing::known_evaluation();
  const std::vector<NamedPlot> evaluation_figures = evaluation_plots(evaluation);
  plots.insert(plots.end(), evaluation_figures.begin(), evaluation_figures.end());
  // A run record as long as report's own (dataset, every step's options): the header must wrap
  // it to the page, not write one line of JSON thousands of pixels wide.
  nlohmann::ordered_json run;
  run["command"] = "report";
  run["dataset"] = {{"path", "/a/rather/long/path/to/a/bop/dataset/" + std::string(60, 'x')},
                    {"split", "test"},
                    {"scenes", "1,2,5-7"}};
  for (const char* step : {"visibility_options", "estimate_options"}) {
    for (int k = 0; k < 30; ++k) run[step]["option_number_" + std::to_string(k)] = 0.125 * k;
    run[step]["nested"] = {{"a_long_list", std::vector<int>(60, 7)}};
  }
  const ReportFiles files = write_report(dir / "report", rows, analysis, plots, run, &evaluation);

  // 1. Load report.html as written: screenshot, and no console output or failed load.
  const std::filesystem::path screenshot = dir / "report_screenshot.png";
  ASSERT_EQ(
      testing::run(chromium_command(dir / "profile1",
                                    "--window-size=1280,4000 --screenshot='" + screenshot.string() +
                                        "' 'file://" + files.report_html.string() + "'",
                                    dir / "out1.txt", dir / "err1.txt")),
      0)
      << testing::read_text(dir / "err1.txt");
  const std::string log = testing::read_text(dir / "err1.txt");
  EXPECT_TRUE(page_errors(log).empty()) << log;
  ASSERT_TRUE(std::filesystem::exists(screenshot)) << log;
  EXPECT_GT(std::filesystem::file_size(screenshot), 10000u);
  // Keep the screenshot in the build folder for people to look at.
  const std::filesystem::path kept = std::filesystem::path(CLUTTERSCOPE_BUILD_DIR) /
                                     "test_artifacts" / "report_browser_screenshot.png";
  std::filesystem::create_directories(kept.parent_path());
  std::filesystem::copy_file(screenshot, kept, std::filesystem::copy_options::overwrite_existing);
  std::cout << "screenshot: " << kept << "\n";

  // 2. The same page with a probe script in <head> (a copy beside the original): it records
  // every element that failed to load and every resource fetched (the report must fetch
  // none: all images are inline data), and once loaded, each figure's <svg> rendered size,
  // into the DOM, which we dump.
  std::string html = testing::read_text(files.report_html);
  const std::string probe =
      "<script>var failed=[];window.addEventListener('error',function(e){var t=e.target;"
      "failed.push('failed '+(t&&(t.src||(t.getAttribute&&t.getAttribute('href')))||"
      "e.message));},true);window.addEventListener('load',function(){var out=failed.slice();"
      "document.querySelectorAll('figure.plot').forEach(function(f){var s=f.querySelector("
      "'svg');var r=s?s.getBoundingClientRect():{width:0,height:0};out.push(f.id+' '+r.width+"
      "' '+r.height);});performance.getEntriesByType('resource').forEach(function(e){out.push("
      "'resource '+e.name);});out.push('page '+document.documentElement.scrollWidth+' '+"
      "window.innerWidth);var pre=document.createElement('pre');pre.id='plot-sizes';"
      "pre.textContent=out.join('\\n');document.body.appendChild(pre);});</script>\n";
  html.insert(html.find("</head>"), probe);
  const std::filesystem::path measured = dir / "report" / "measure.html";
  testing::write_text(measured, html);
  ASSERT_EQ(
      testing::run(chromium_command(
          dir / "profile2", "--window-size=1280,900 --dump-dom 'file://" + measured.string() + "'",
          dir / "dom.html", dir / "err2.txt")),
      0)
      << testing::read_text(dir / "err2.txt");
  EXPECT_TRUE(page_errors(testing::read_text(dir / "err2.txt")).empty())
      << testing::read_text(dir / "err2.txt");
  const std::string dom = testing::read_text(dir / "dom.html");
  // Every section rendered, the evaluation's among them.
  for (const char* id :
       {"summary", "correlations", "bands", "calibration", "thresholds", "evaluation",
        "evaluation-average-recalls", "evaluation-bands", "evaluation-correlation",
        "evaluation-score", "evaluation-bands_scene", "plots"}) {
    EXPECT_NE(dom.find("id=\"" + std::string(id) + "\""), std::string::npos) << id;
  }
  const size_t begin = dom.find("<pre id=\"plot-sizes\">");
  ASSERT_NE(begin, std::string::npos) << dom.substr(0, 2000);
  const size_t end = dom.find("</pre>", begin);
  std::istringstream sizes(dom.substr(begin + 21, end - begin - 21));
  std::map<std::string, std::pair<double, double>> measured_sizes;
  bool page_measured = false;
  for (std::string line; std::getline(sizes, line);) {
    std::istringstream fields(line);
    std::string id;
    fields >> id;
    if (id == "page") {
      // The page scrolls vertically only: nothing (header, table, figure) is wider than the
      // 1280 px window.
      double scroll_width = 0, viewport_width = 0;
      fields >> scroll_width >> viewport_width;
      EXPECT_GT(viewport_width, 0.0) << line;
      EXPECT_LE(scroll_width, viewport_width) << line;
      page_measured = true;
      continue;
    }
    ASSERT_NE(id, "resource") << "the report fetched " << line;
    ASSERT_NE(id, "failed") << "an element of the report failed to load: " << line;
    double width = 0, height = 0;
    fields >> width >> height;
    measured_sizes[id] = {width, height};
  }
  EXPECT_TRUE(page_measured);
  ASSERT_EQ(measured_sizes.size(), plots.size());
  for (const NamedPlot& plot : plots) {
    const auto found = measured_sizes.find("plot-" + plot.name);
    ASSERT_NE(found, measured_sizes.end()) << plot.name;
    EXPECT_GT(found->second.first, 100.0) << plot.name;
    EXPECT_GT(found->second.second, 50.0) << plot.name;
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace clutterscope::report
