#version 450
// G-buffer pass, vertex stage: world-space attributes straight through, except that the
// moving light's own geometry follows the light: it is drawn once per copy of the light, each
// draw with that copy's offset and emission scale.

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in uint in_object;
layout(location = 3) in uint in_material;
layout(location = 4) in vec2 in_uv;
layout(location = 5) in vec4 in_tangent;

layout(push_constant) uniform Frame {
    mat4 view_projection;
    vec4 eye;
    vec4 light_offset;
    vec4 light_scale;
    uint light_object; // object id + 1 of the moving light; 0: none
} frame;

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;
layout(location = 2) flat out uint out_object;
layout(location = 3) flat out uint out_material;
layout(location = 4) out vec2 out_uv;
layout(location = 5) out vec4 out_tangent;
// What the emission is multiplied by: the light copy's scale on the moving light, else 1.
layout(location = 6) flat out vec3 out_emission_scale;

void main() {
    bool moving = in_object + 1u == frame.light_object;
    vec3 position = in_position + (moving ? frame.light_offset.xyz : vec3(0.0));
    out_emission_scale = moving ? frame.light_scale.rgb : vec3(1.0);
    out_position = position;
    out_normal = in_normal;
    out_object = in_object;
    out_material = in_material;
    out_uv = in_uv;
    out_tangent = in_tangent;
    gl_Position = frame.view_projection * vec4(position, 1.0);
}
