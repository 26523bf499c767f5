// Display transform: exposure, then the ACES filmic curve fitted by Narkowicz (2015), then
// the sRGB transfer function. Mirrored line for line by renderer/src/passes/tonemap.rs.
#ifndef RRF_TONEMAP_GLSL
#define RRF_TONEMAP_GLSL

vec3 aces_fitted(vec3 x) {
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 linear_to_srgb(vec3 c) {
    vec3 low = 12.92 * c;
    vec3 high = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return mix(high, low, lessThanEqual(c, vec3(0.0031308)));
}

// Linear HDR radiance to display-referred sRGB in [0, 1]; `exposure_scale` is 2^EV.
vec3 tonemap(vec3 radiance, float exposure_scale) {
    return linear_to_srgb(aces_fitted(max(radiance, vec3(0.0)) * exposure_scale));
}

#endif
