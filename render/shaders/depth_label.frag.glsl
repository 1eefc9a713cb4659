#version 330 core
{{DEFINES}}

layout(location = 0) out float depth_out;
layout(location = 1) out uint label_out;

{{SURFACE_UNIFORMS}}

{{SURFACE_DEPTH}}

void main() {
  depth_out = surface_z(model_view, ray, tile_origin, depth_map);
  label_out = label;
}
