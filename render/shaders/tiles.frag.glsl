#version 330 core
{{DEFINES}}

layout(location = 0) out float depth_out;
layout(location = 1) out uint label_out;
flat in mat4 tile_model_view;
flat in vec4 tile_ray;
flat in vec4 tile_origin_depth_map;
flat in uint tile_label;

{{SURFACE_DEPTH}}

void main() {
  depth_out = surface_z(tile_model_view, tile_ray, tile_origin_depth_map.xy,
                        tile_origin_depth_map.zw);
  label_out = tile_label;
}
