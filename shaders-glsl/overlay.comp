#version 450
// Overlay pass: text in the 8x8 public-domain font over the display image, each glyph pixel
// scaled to `scale` screen pixels, on a darkened box. One invocation per pixel of the text box.

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = 0, rgba8) uniform image2D display;
// 128 glyphs of 8 rows, one byte per row (bit 0 is the leftmost pixel), four rows per word.
layout(std430, binding = 1) readonly buffer Glyphs { uint glyphs[256]; };
// One cell per word, row-major: bits 0-7 the character (0: transparent), bits 8-15 the colour.
layout(std430, binding = 2) readonly buffer Text { uint cells[]; };

layout(push_constant) uniform Params {
    ivec2 origin;
    uint columns;
    uint rows;
    uint scale;
} params;

const vec3 PALETTE[4] = vec3[4](vec3(1.0), vec3(1.0, 0.85, 0.3), vec3(1.0, 0.35, 0.3), vec3(0.55, 0.85, 1.0));

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    ivec2 pixel = params.origin + ivec2(p);
    if (any(greaterThanEqual(pixel, imageSize(display)))) {
        return;
    }
    uvec2 cell = p / (8u * params.scale);
    if (cell.x >= params.columns || cell.y >= params.rows) {
        return;
    }
    uint word = cells[cell.y * params.columns + cell.x];
    uint ch = word & 0x7fu;
    if (ch == 0u) {
        return;
    }
    uvec2 inner = (p / params.scale) % 8u;
    uint bits = (glyphs[ch * 2u + inner.y / 4u] >> ((inner.y % 4u) * 8u)) & 0xffu;
    bool lit = ((bits >> inner.x) & 1u) != 0u;
    vec3 under = imageLoad(display, pixel).rgb;
    imageStore(display, pixel, vec4(lit ? PALETTE[(word >> 8u) & 3u] : under * 0.3, 1.0));
}
