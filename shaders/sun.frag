#version 450 core
// Sun item buffer: the ID of the patch nearest the sun (0: nothing).
flat in uint v_id;
layout(location = 0) out uint o_id;
void main() { o_id = v_id; }
