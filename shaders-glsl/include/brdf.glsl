// The baker's BRDF (baker/src/trace/bsdf.rs, `Bsdf::eval`) for the network pass's analytic
// direct light: glTF metallic-roughness with the KHR_materials_specular factor, Lambert plus
// GGX with Smith height-correlated masking-shadowing and Schlick Fresnel, α = roughness² (at
// least MIN_ALPHA). tests/brdf.rs holds it to the baker's on random inputs.
#ifndef RRF_BRDF_GLSL
#define RRF_BRDF_GLSL

const float BRDF_PI = 3.14159265358979;
// bsdf.rs's MIN_ALPHA.
const float MIN_ALPHA = 1e-3;

vec3 brdf_schlick(vec3 f0, float c) {
    float m = clamp(1.0 - c, 0.0, 1.0);
    float m5 = (m * m) * (m * m) * m;
    return f0 + (vec3(1.0) - f0) * m5;
}

// Smith Λ for GGX, of a direction at cosine `c` to the normal.
float ggx_lambda(float alpha, float c) {
    float tan2 = max(1.0 - c * c, 0.0) / (c * c);
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

// f(wo, wi) at a surface of normal `n`; zero unless both are above it.
vec3 brdf_eval(vec3 base_color, float metallic, float roughness, float specular, vec3 n, vec3 wo, vec3 wi) {
    float no = dot(n, wo);
    float ni = dot(n, wi);
    if (no <= 0.0 || ni <= 0.0) {
        return vec3(0.0);
    }
    if (specular == 0.0 && metallic == 0.0) {
        return base_color / BRDF_PI;
    }
    float alpha = max(roughness * roughness, MIN_ALPHA);
    vec3 h = normalize(wo + wi);
    float vh = max(dot(wo, h), 0.0);
    float nh = dot(n, h);
    float a2 = alpha * alpha;
    float t = nh * nh * (a2 - 1.0) + 1.0;
    float d = a2 / (BRDF_PI * t * t);
    float g2 = 1.0 / (1.0 + ggx_lambda(alpha, no) + ggx_lambda(alpha, ni));
    float f_d = specular * brdf_schlick(vec3(0.04), vh).x;
    vec3 f_m = brdf_schlick(base_color, vh);
    vec3 diffuse = (1.0 - metallic) * (1.0 - f_d) * base_color / BRDF_PI;
    vec3 fresnel = (1.0 - metallic) * vec3(f_d) + metallic * f_m;
    return diffuse + fresnel * (d * g2 / (4.0 * no * ni));
}

#endif
