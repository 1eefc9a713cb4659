#pragma once

// JSON helpers shared by the BOP reader and writer: parsing with errors that say where, typed
// field access with validation, and bop_toolkit's save_json layout.

#include <Eigen/Core>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace clutterscope::datasets::detail {

using Json = nlohmann::json;

// Reads and parses a JSON file. `where` ("scene 3: " or "") prefixes error messages. A parse
// error names the parser's message, the top-level key it happened in ("image 12" when
// key_name is "image") and the last field name read before it.
Json read_json_file(const std::filesystem::path& path, const std::string& where,
                    const char* key_name = "entry");

// Where a field lives: the file and the location prefix ("scene 3, image 12, gt 4: ").
struct FieldContext {
  std::filesystem::path file;
  std::string where;

  [[noreturn]] void fail(const std::string& message) const;
};

// The value of `field` in `object`; DatasetError when missing.
const Json& require_field(const Json& object, const char* field, const FieldContext& context);
// A finite number.
double finite_number(const Json& value, const char* field, const FieldContext& context);
// An integer (a JSON number with no fractional part).
int integer(const Json& value, const char* field, const FieldContext& context);
// Exactly `count` finite numbers.
std::vector<double> finite_numbers(const Json& value, const char* field, size_t count,
                                   const FieldContext& context);
// A 3x3 matrix from 9 row-major values.
Eigen::Matrix3d row_major_matrix(const Json& value, const char* field, const FieldContext& context);
// Whether `matrix` is a rotation within `tolerance`: max |R^T R - I| at most the tolerance and
// det(R) within 3 tolerance of +1; otherwise `why` says which ("not a rotation: ...").
bool is_rotation(const Eigen::Matrix3d& matrix, double tolerance, std::string* why);
// A rotation: 9 row-major values with |R^T R - I| (largest entry) within `tolerance` and
// det(R) > 0, returned exactly as given (no re-orthonormalisation: bop_toolkit renders the
// stored values, and exact scene_gt_info.json counts depend on it). The default tolerance
// accepts the rounding of published BOP files (LM-O reaches about 1e-2).
Eigen::Matrix3d rotation(const Json& value, const char* field, const FieldContext& context,
                         double tolerance = kRotationOrthonormalityTolerance);
Eigen::Vector3d vector3(const Json& value, const char* field, const FieldContext& context);

// Intrinsics the reader accepts (scene_camera.json cam_K, camera.json fx/fy/cx/cy), in pixels.
// A focal length below 1 px puts a 640 px image across 179.8 degrees: no pinhole camera, and
// fx = 1e-300 collapses every object to a point. Above 1e6 px a 4096 px image spans 0.23
// degrees; BOP's cameras have 500-4000 px. The principal point must lie on the 3W x 3H canvas
// centred on the image that visibility renders on: cx in [-W, 2W], cy in [-H, 2H].
constexpr double kMinFocalLengthPx = 1.0;
constexpr double kMaxFocalLengthPx = 1e6;

// Refuses intrinsics outside kMinFocalLengthPx..kMaxFocalLengthPx (fx, fy) or a principal
// point off the 3W x 3H canvas, naming `field` ("cam_K", "camera.json") and the value.
void check_intrinsics(double fx, double fy, double cx, double cy, int width, int height,
                      const char* field, const FieldContext& context);

// Parses an object key as an integer id ("12" -> 12); DatasetError otherwise.
int key_as_id(const std::string& key, const char* what, const FieldContext& context);

// Python's json.dumps(value, sort_keys=True): ", " and ": " separators, keys sorted.
std::string python_dumps(const Json& value);
// bop_toolkit's inout.save_json of a dict with integer keys: one entry per line, keys sorted
// numerically.
std::string bop_dump(const std::map<int, Json>& entries);

}  // namespace clutterscope::datasets::detail
