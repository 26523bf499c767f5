#version 450
#extension GL_GOOGLE_include_directive : require
// Mirror pass: adds to a planar mirror's pixels what it reflects. The reflection images are
// the network pass's outputs for the scene drawn seen in the mirror's plane, so the point a
// mirror pixel reflects lies at the same pixel of them. A mirror pixel gets them weighted by
// its Fresnel term (Schlick, F0 its base colour) and split as the path tracer splits a
// mirror's light: the emission seen in it is its direct light, the light that other surfaces
// reflect to it is indirect. The CPU twin is `Predictor::seen` in `baker/src/predict.rs`.

#include "brdf.glsl"
#include "gbuffer_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0, rgba32ui) uniform readonly uimage2D surface;
layout(binding = 1, r32ui) uniform readonly uimage2D ids;
layout(binding = 2, rgba32ui) uniform readonly uimage2D shading;
layout(binding = 3, rgba32f) uniform readonly image2D seen_direct;
layout(binding = 4, rgba32f) uniform readonly image2D seen_indirect;
layout(binding = 5, rgba32f) uniform readonly image2D seen_gi;
layout(binding = 6, rgba32f) uniform image2D out_direct;
layout(binding = 7, rgba32f) uniform image2D out_indirect;
layout(binding = 8, rgba32f) uniform image2D out_gi;

layout(push_constant) uniform Params {
    // xyz: the camera.
    vec4 eye;
    // xyz: the mirror plane's unit normal on the camera's side.
    vec4 normal;
    // The mirror's object id + 1, as the G-buffer holds it.
    uint object;
    // The first pixel dispatched.
    uvec2 origin;
} params;

void main() {
    ivec2 pixel = ivec2(params.origin + gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(out_gi))) || id_object(imageLoad(ids, pixel).x) != params.object) {
        return;
    }
    vec3 p = uintBitsToFloat(imageLoad(surface, pixel).xyz);
    float cos_theta = clamp(dot(normalize(params.eye.xyz - p), params.normal.xyz), 0.0, 1.0);
    vec3 f = brdf_schlick(decode_shading(imageLoad(shading, pixel)).base_color, cos_theta);
    vec3 seen_direct_light = imageLoad(seen_direct, pixel).rgb;
    vec3 seen_indirect_light = imageLoad(seen_indirect, pixel).rgb;
    vec3 seen_all = imageLoad(seen_gi, pixel).rgb;
    vec3 seen_emission = seen_all - seen_direct_light - seen_indirect_light;
    vec4 direct = imageLoad(out_direct, pixel);
    vec4 indirect = imageLoad(out_indirect, pixel);
    vec4 gi = imageLoad(out_gi, pixel);
    imageStore(out_direct, pixel, vec4(direct.rgb + f * seen_emission, direct.a));
    imageStore(out_indirect, pixel, vec4(indirect.rgb + f * (seen_direct_light + seen_indirect_light), indirect.a));
    imageStore(out_gi, pixel, vec4(gi.rgb + f * seen_all, gi.a));
}
