/* A full-screen triangle: three vertices in clip space cover the target. */

void main()
{
  gl_Position = vec4(pos, 0.0, 1.0);
}
