#version 450
#extension GL_GOOGLE_include_directive : require
// Test-only: brdf.glsl's `brdf_eval` on a list of cases, so that tests/brdf.rs can hold it to
// the baker's `Bsdf::eval`. Per case, 16 floats in: base colour (3), metallic, roughness,
// specular, normal (3), wo (3), wi (3), unused; 4 floats out: f (3), unused.

layout(local_size_x = 64) in;

#include "brdf.glsl"

layout(std430, binding = 0) readonly buffer Cases { float cases[]; };
layout(std430, binding = 1) writeonly buffer Values { vec4 values[]; };

layout(push_constant) uniform Count {
    uint count;
} push;

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) {
        return;
    }
    uint c = 16u * i;
    vec3 base = vec3(cases[c], cases[c + 1u], cases[c + 2u]);
    vec3 n = vec3(cases[c + 6u], cases[c + 7u], cases[c + 8u]);
    vec3 wo = vec3(cases[c + 9u], cases[c + 10u], cases[c + 11u]);
    vec3 wi = vec3(cases[c + 12u], cases[c + 13u], cases[c + 14u]);
    values[i] = vec4(brdf_eval(base, cases[c + 3u], cases[c + 4u], cases[c + 5u], n, wo, wi), 0.0);
}
