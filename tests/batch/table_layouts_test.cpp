#include <gtest/gtest.h>

#include <clutterscope/batch/table_layouts.hpp>

namespace clutterscope::batch {
namespace {

// The headers are part of the output bytes: existing folders resume and merge with them.
TEST(TableLayouts, HeadersAsWritten) {
  EXPECT_EQ(visibility_objects_table().header(),
            "split,scene_id,im_id,gt_id,obj_id,label,px_count_all,px_count_valid,"
            "px_count_visib,visib_fract,bbox_obj_x,bbox_obj_y,bbox_obj_w,bbox_obj_h,"
            "bbox_visib_x,bbox_visib_y,bbox_visib_w,bbox_visib_h,in_view");
  EXPECT_EQ(visibility_images_table().header(), "split,scene_id,im_id,n_objects,scene_visibility");
  EXPECT_EQ(estimates_table().header(),
            "split,scene_id,im_id,gt_id,obj_id,label,x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,"
            "var_z_cm2,cov_xy_cm2,cov_xz_cm2,cov_yz_cm2,confident,err_cm,init_err_cm,err_x_cm,"
            "err_y_cm,err_z_cm,nees,radius95_cm,confident_radius,ess_min,seen_through,"
            "belief_shift,consistent,other_fits,time_ms");
  EXPECT_EQ(bop_results_table().header(), "scene_id,im_id,obj_id,score,R,t,time");
  EXPECT_EQ(belief_samples_table().header(), "gt_id,obj_id,iteration,x_mm,y_mm,z_mm,weight");
  EXPECT_EQ(report_objects_table().header(),
            visibility_objects_table().header() +
                ",x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,var_z_cm2,cov_xy_cm2,cov_xz_cm2,cov_yz_cm2,"
                "max_var_cm2,confident,err_cm,"
                "init_err_cm,err_x_cm,err_y_cm,err_z_cm,nees,radius95_cm,confident_radius,"
                "ess_min,time_ms,consistent");
  EXPECT_EQ(report_images_table().header(),
            "split,scene_id,im_id,n_objects,scene_visibility,n_estimated,n_confident,"
            "mean_max_var_cm2");
}

TEST(TableLayouts, FileNamesAndSpec) {
  EXPECT_EQ(visibility_objects_table().file_name, "objects.csv");
  EXPECT_EQ(estimates_table().spec().file_name, "estimates.csv");
  EXPECT_EQ(estimates_table().spec().header, estimates_table().header());
}

// Readers require the columns of a table's first version only.
TEST(TableLayouts, RequiredColumns) {
  EXPECT_EQ(estimates_table().required_columns(),
            (std::vector<std::string>{"split", "scene_id", "im_id", "gt_id", "obj_id", "x_mm",
                                      "y_mm", "z_mm", "var_x_cm2", "var_y_cm2", "var_z_cm2",
                                      "confident", "err_cm"}));
  EXPECT_EQ(visibility_images_table().required_columns().size(), 5u);
  EXPECT_EQ(report_objects_table().required_columns().size(), 18u + 8u);
}

}  // namespace
}  // namespace clutterscope::batch
