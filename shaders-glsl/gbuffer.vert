#version 450
// G-buffer pass, vertex stage: world-space attributes straight through.

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_emission_roughness;
layout(location = 3) in uint in_object;

layout(push_constant) uniform Camera {
    mat4 view_projection;
    vec4 eye;
} camera;

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec4 out_emission_roughness;
layout(location = 3) flat out uint out_object;

void main() {
    out_position = in_position;
    out_normal = in_normal;
    out_emission_roughness = in_emission_roughness;
    out_object = in_object;
    gl_Position = camera.view_projection * vec4(in_position, 1.0);
}
