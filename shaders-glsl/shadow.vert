#version 450
#extension GL_GOOGLE_include_directive : require
// Shadow pass, vertex stage: the scene seen from a point light through one face of its cube
// (shadow_cube.glsl); the viewport puts the face in its place in the atlas.

#include "shadow_cube.glsl"

layout(location = 0) in vec3 in_position;

layout(push_constant) uniform Face {
    vec4 light;
    uint face;
} push;

layout(location = 0) out vec3 out_offset;

void main() {
    out_offset = in_position - push.light.xyz;
    gl_Position = cube_face_clip(out_offset, push.face);
}
