#version 450
// Shadow pass, fragment stage: the distance from the light, which the network pass compares
// a surface's own distance against.

layout(location = 0) in vec3 in_offset;
layout(location = 0) out float out_distance;

void main() {
    out_distance = length(in_offset);
}
