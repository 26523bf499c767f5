// Materials and textures as the G-buffer pass reads them (renderer/src/passes/mesh.rs:
// `SurfaceMaterial`, `TextureRef`), sampled exactly as the path tracer samples them
// (`Material::shading` and `Texture::sample` in baker/src/scene/): bilinear, repeating, no
// mipmaps, sRGB decoded per texel before filtering. So the networks see the same inputs on
// the GPU as in their training samples.
#ifndef RRF_GBUFFER_MATERIALS_GLSL
#define RRF_GBUFFER_MATERIALS_GLSL

struct TextureRef {
    vec4 matrix;      // row-major 2×2: uv' = matrix · uv + offset (KHR_texture_transform)
    vec2 offset;
    uint first_texel; // into `texels`
    uint shape;       // bits 0-14 width, 15-29 height, 30 sRGB, 31 used at all
};

struct SurfaceMaterial {
    vec4 base_color;  // rgb factor, a alpha factor
    vec4 factors;     // metallic, roughness, normal scale, alpha cutoff (negative: opaque)
    TextureRef textures[4]; // base colour, metallic-roughness, normal, emissive
    uint emits_back;  // 1: emits from the back face too (glTF doubleSided)
};

layout(std430, set = 0, binding = 0) readonly buffer Materials { SurfaceMaterial materials[]; };
// RGBA8 texels, r in the low byte.
layout(std430, set = 0, binding = 1) readonly buffer Texels { uint texels[]; };

const uint TEXTURE_SRGB = 1u << 30;
const uint TEXTURE_PRESENT = 1u << 31;

float srgb_to_linear(float c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

// x modulo n into [0, n), for either sign of x (integer division truncates toward zero).
int wrap(int x, int n) {
    int r = x - n * (x / n);
    return r < 0 ? r + n : r;
}

vec4 texel(TextureRef t, ivec2 size, int x, int y) {
    vec4 v = unpackUnorm4x8(texels[t.first_texel + uint(wrap(y, size.y) * size.x + wrap(x, size.x))]);
    if ((t.shape & TEXTURE_SRGB) != 0u) {
        v.rgb = vec3(srgb_to_linear(v.r), srgb_to_linear(v.g), srgb_to_linear(v.b));
    }
    return v;
}

// The texture at `uv` (before its transform), or 1 where the material has none.
vec4 sample_texture(TextureRef t, vec2 uv) {
    if ((t.shape & TEXTURE_PRESENT) == 0u) {
        return vec4(1.0);
    }
    ivec2 size = ivec2(t.shape & 0x7fffu, (t.shape >> 15) & 0x7fffu);
    vec2 st = vec2(dot(t.matrix.xy, uv), dot(t.matrix.zw, uv)) + t.offset;
    vec2 p = st * vec2(size) - 0.5;
    vec2 corner = floor(p);
    vec2 f = p - corner;
    ivec2 i = ivec2(corner);
    vec4 top = mix(texel(t, size, i.x, i.y), texel(t, size, i.x + 1, i.y), f.x);
    vec4 bottom = mix(texel(t, size, i.x, i.y + 1), texel(t, size, i.x + 1, i.y + 1), f.x);
    return mix(top, bottom, f.y);
}

// The shading normal from normal map value `m` (tangent space, scaled) on a surface of
// interpolated `normal` (unit) and `tangent` (w: the bitangent's sign), as glTF says; the
// twin of `normal_mapped` in baker/src/trace/world.rs.
vec3 normal_mapped(vec3 normal, vec4 tangent, vec3 m) {
    vec3 t = tangent.xyz - normal * dot(normal, tangent.xyz);
    float length_t = length(t);
    if (length_t > 0.0) {
        t /= length_t;
    } else {
        t = abs(normal.x) > 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
        t = normalize(t - normal * dot(normal, t));
    }
    vec3 b = cross(normal, t) * (tangent.w < 0.0 ? -1.0 : 1.0);
    vec3 n = t * m.x + b * m.y + normal * m.z;
    float length_n = length(n);
    return length_n > 0.0 ? n / length_n : normal;
}

#endif
