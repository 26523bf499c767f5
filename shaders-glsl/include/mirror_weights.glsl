// What the network shaders need to shade a pixel that shows what a planar mirror reflects:
// where the mirror's merge step (mirror_merge.comp) put the reflected point into the frame's
// G-buffer, flagging its id (gbuffer_layout.glsl, `id_reflected`), it also wrote the mirror's
// Fresnel weight (rgb) and the mirror's index among the frame's mirrors (a) here.
//
// Before including: network_interface.glsl.
#ifndef RRF_MIRROR_WEIGHTS_GLSL
#define RRF_MIRROR_WEIGHTS_GLSL

layout(binding = MIRROR_BINDING, rgba16f) uniform readonly image2D mirror_weights;

// Radiance leaving a point seen in a mirror, as the mirror's pixel shows it: weighted by the
// mirror's Fresnel term `fresnel` and split as the path tracer splits a mirror's light (the
// emission seen in it is its direct light, the light other surfaces reflect to it indirect;
// `Predictor::seen` in baker/src/predict.rs is the CPU twin). A mirror emits nothing itself.
void seen_in_mirror(vec3 fresnel, inout vec3 emission, inout vec3 direct, inout vec3 indirect) {
    vec3 reflected_emission = fresnel * emission;
    indirect = fresnel * (direct + indirect);
    direct = reflected_emission;
    emission = vec3(0.0);
}

#endif
