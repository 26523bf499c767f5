#version 450
// User interface: the vertex colour times the texture, both sRGB-encoded with premultiplied
// alpha; the pipeline blends the result over the display image (ONE, ONE_MINUS_SRC_ALPHA).

layout(binding = 0) uniform sampler2D texels;

layout(location = 0) in vec2 v_uv;
layout(location = 1) in vec4 v_colour;

layout(location = 0) out vec4 colour;

void main() {
    colour = v_colour * texture(texels, v_uv);
}
