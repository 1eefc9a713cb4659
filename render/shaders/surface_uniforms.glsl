uniform mat4 model_view;
uniform vec4 ray;
uniform vec2 tile_origin;
uniform vec2 depth_map;
uniform uint label;
