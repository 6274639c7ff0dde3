// The vertex stage of the passes that shade every texel of their target: vertex
// gl_VertexID (0, 1, 2) of one triangle covering the whole viewport (clip space),
// drawn as three vertices without attributes.
#if defined VERTEX_SHADER
void main() {
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
#endif
