in float camera_z;
#ifdef EXACT_DEPTH
uniform samplerBuffer planes;     // model-frame plane (n, d) of each triangle: n.x = d
float surface_z(mat4 model_view, vec4 ray, vec2 tile_origin, vec2 depth_map) {
  vec4 plane = texelFetch(planes, gl_PrimitiveID);
  vec3 n = mat3(model_view) * plane.xyz;
  float d = plane.w + dot(n, model_view[3].xyz);
  vec2 p = gl_FragCoord.xy - tile_origin;
  vec3 r = vec3((p.x - ray.x) / ray.z, (p.y - ray.y) / ray.w, 1.0);
  float z = d / dot(n, r);
  // Grazing or degenerate triangles: the interpolated depth is the better estimate there.
  if (!(abs(z - camera_z) <= 1e-3 * camera_z)) z = camera_z;
  gl_FragDepth = depth_map.x / z + depth_map.y;
  return z;
}
#else
float surface_z(mat4 model_view, vec4 ray, vec2 tile_origin, vec2 depth_map) { return camera_z; }
#endif
