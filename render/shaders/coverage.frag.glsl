#version 430 core
{{DEFINES}}

layout(binding = 0, r32ui) uniform uimage2DArray coverage;
uniform int coverage_layer;
uniform uint coverage_bit;
layout(location = 0) out float depth_out;
layout(location = 1) out uint label_out;

{{SURFACE_UNIFORMS}}

{{SURFACE_DEPTH}}

void main() {
  imageAtomicOr(coverage, ivec3(ivec2(gl_FragCoord.xy), coverage_layer), coverage_bit);
  depth_out = surface_z(model_view, ray, tile_origin, depth_map);
  label_out = label;
}
