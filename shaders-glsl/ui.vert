#version 450
// User interface: a vertex in points from the top-left corner to clip space (Vulkan's y
// points down, as the points do). See renderer/src/passes/ui.rs.

layout(location = 0) in vec2 position;
layout(location = 1) in vec2 uv;
// sRGB-encoded, premultiplied alpha (read as UNORM, so still encoded).
layout(location = 2) in vec4 colour;

layout(push_constant) uniform Params {
    vec2 screen_points;
} params;

layout(location = 0) out vec2 v_uv;
layout(location = 1) out vec4 v_colour;

void main() {
    gl_Position = vec4(2.0 * position / params.screen_points - 1.0, 0.0, 1.0);
    v_uv = uv;
    v_colour = colour;
}
