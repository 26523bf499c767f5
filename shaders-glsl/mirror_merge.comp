#version 450
#extension GL_GOOGLE_include_directive : require
// Mirror merge: puts what a planar mirror reflects into the frame's G-buffer, so that the
// frame's one network pass shades it with every other pixel. The reflection's G-buffer holds
// the scene drawn from the camera reflected in the mirror's plane, so the point a mirror pixel
// reflects lies at the same pixel of it. At each pixel where the frame sees this mirror, the
// step copies that point's texels over the mirror's, flags its id as reflected, and writes
// the mirror's Fresnel weight (Schlick, F0 its base colour, at the angle the camera sees it)
// and the mirror's index among the frame's mirrors, which picks the reflected camera's eye
// (network_inputs.glsl). Pixels already flagged show another mirror's reflection: one
// reflection, as the CPU twin `Predictor::seen` in baker/src/predict.rs draws it.

#include "brdf.glsl"
#include "gbuffer_layout.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0, rgba32ui) uniform uimage2D frame_surface;
layout(binding = 1, r32ui) uniform uimage2D frame_ids;
layout(binding = 2, rgba32ui) uniform uimage2D frame_shading;
layout(binding = 3, rgba32ui) uniform readonly uimage2D seen_surface;
layout(binding = 4, r32ui) uniform readonly uimage2D seen_ids;
layout(binding = 5, rgba32ui) uniform readonly uimage2D seen_shading;
layout(binding = 6, rgba16f) uniform writeonly image2D mirror_weights;

layout(push_constant) uniform Params {
    // xyz: the camera.
    vec4 eye;
    // xyz: the mirror plane's unit normal on the camera's side.
    vec4 normal;
    // The mirror's object id + 1, as the G-buffer holds it.
    uint object;
    // The mirror's index among the frame's mirrors.
    uint slot;
    // The first pixel dispatched.
    uvec2 origin;
} params;

void main() {
    ivec2 pixel = ivec2(params.origin + gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(frame_ids)))) {
        return;
    }
    uint id = imageLoad(frame_ids, pixel).x;
    if (id_object(id) != params.object || id_reflected(id)) {
        return;
    }
    vec3 p = uintBitsToFloat(imageLoad(frame_surface, pixel).xyz);
    float cos_theta = clamp(dot(normalize(params.eye.xyz - p), params.normal.xyz), 0.0, 1.0);
    vec3 fresnel = brdf_schlick(decode_shading(imageLoad(frame_shading, pixel)).base_color, cos_theta);
    imageStore(mirror_weights, pixel, vec4(fresnel, float(params.slot)));
    imageStore(frame_surface, pixel, imageLoad(seen_surface, pixel));
    imageStore(frame_ids, pixel, uvec4(imageLoad(seen_ids, pixel).x | ID_REFLECTED));
    imageStore(frame_shading, pixel, imageLoad(seen_shading, pixel));
}
