#version 330 core
layout(location = 0) in vec3 position;
uniform mat4 model_view;
uniform mat4 projection;
out float camera_z;
void main() {
  vec4 camera = model_view * vec4(position, 1.0);
  camera_z = camera.z;
  gl_Position = projection * camera;
}
