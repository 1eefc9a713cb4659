#version 330 core
{{EXTENSIONS}}
layout(location = 0) in vec3 position;
uniform samplerBuffer tiles;
uniform int first_tile;
out float camera_z;
flat out mat4 tile_model_view;
flat out vec4 tile_ray;
flat out vec4 tile_origin_depth_map;
flat out uint tile_label;
void main() {
  int base = (first_tile + gl_InstanceID) * {{TEXELS_PER_TILE}};
  mat4 model_view = mat4(texelFetch(tiles, base), texelFetch(tiles, base + 1),
                         texelFetch(tiles, base + 2), texelFetch(tiles, base + 3));
  mat4 projection = mat4(texelFetch(tiles, base + 4), texelFetch(tiles, base + 5),
                         texelFetch(tiles, base + 6), texelFetch(tiles, base + 7));
  vec4 camera = model_view * vec4(position, 1.0);
  camera_z = camera.z;
  gl_Position = projection * camera;
  tile_model_view = model_view;
  tile_ray = texelFetch(tiles, base + 8);
  tile_origin_depth_map = texelFetch(tiles, base + 9);
  vec4 label = texelFetch(tiles, base + 10);
  tile_label = uint(label.x) | (uint(label.y) << 16);
{{SELECT_VIEWPORT}}
}
