#version 450
#extension GL_GOOGLE_include_directive : require
// G-buffer pass, fragment stage: the packed surface (gbuffer_layout.glsl). The shading normal
// faces the viewer, as the path tracer's does.

#include "gbuffer_layout.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) flat in uint in_object;
layout(location = 3) flat in uint in_material;

layout(location = 0) out uvec4 out_surface;
layout(location = 1) out uint out_id;

void main() {
    vec3 n = normalize(in_normal);
    out_surface = uvec4(floatBitsToUint(in_position), encode_normal(gl_FrontFacing ? n : -n));
    // Object ids are stored +1 so that 0 means "nothing here".
    out_id = encode_id(in_object + 1u, in_material, gl_FrontFacing);
}
