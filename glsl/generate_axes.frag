// generate_axes.frag -- the texel generate_axes.vert computed, as it is.
flat in vec4 v_value;
out vec4 f_value;

void main() {
    f_value = v_value;
}
