#version 450 core
// ffcube view, picking: 1 + the patch index into an R32UI target (0 stays "nothing here").
flat in uint v_patch;

layout(location = 0) out uint item;

void main() {
    item = v_patch + 1u;
}
