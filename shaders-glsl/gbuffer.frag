#version 450
#extension GL_GOOGLE_include_directive : require
// G-buffer pass, fragment stage: the packed surface (gbuffer_layout.glsl) with the material's
// textures applied as the path tracer applies them (`Material::shading`, `World::interaction`):
// alpha-masked texels are not there, the normal map bends the shading normal, and the shading
// normal faces the viewer.

#include "gbuffer_layout.glsl"
#include "gbuffer_materials.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) flat in uint in_object;
layout(location = 3) flat in uint in_material;
layout(location = 4) in vec2 in_uv;
layout(location = 5) in vec4 in_tangent;
layout(location = 6) flat in vec3 in_emission_scale;

// Whether this pipeline's draws use textures; without, the texture code is compiled out.
layout(constant_id = 0) const bool TEXTURED = true;

layout(location = 0) out uvec4 out_surface;
layout(location = 1) out uint out_id;
layout(location = 2) out uvec4 out_shading;

void main() {
    uint m = in_material;
    vec4 base = materials[m].base_color;
    vec4 factors = materials[m].factors;
    vec4 metallic_roughness = vec4(1.0);
    vec3 emissive = vec3(1.0);
    vec3 n = normalize(in_normal);
    if (TEXTURED) {
        base *= sample_texture(materials[m].textures[0], in_uv);
        metallic_roughness = sample_texture(materials[m].textures[1], in_uv);
        emissive = sample_texture(materials[m].textures[3], in_uv).rgb;
        if ((materials[m].textures[2].shape & TEXTURE_PRESENT) != 0u) {
            vec3 t = sample_texture(materials[m].textures[2], in_uv).xyz * 2.0 - 1.0;
            n = normal_mapped(n, in_tangent, vec3(t.xy * factors.z, t.z));
        }
    }
    if (factors.w >= 0.0 && base.a < factors.w) {
        discard;
    }
    // A face that does not emit gets no emission at all (emitters emit from the front only,
    // unless double-sided).
    if (!gl_FrontFacing && materials[m].emits_back == 0u) {
        emissive = vec3(0.0);
    }
    emissive *= in_emission_scale;
    Shading shading = Shading(base.rgb, emissive, factors.y * metallic_roughness.g, factors.x * metallic_roughness.b);
    out_surface = uvec4(floatBitsToUint(in_position), encode_normal(gl_FrontFacing ? n : -n));
    // Object ids are stored +1 so that 0 means "nothing here".
    out_id = encode_id(in_object + 1u, in_material, gl_FrontFacing);
    out_shading = encode_shading(shading);
}
