/* A full-screen triangle at the far plane: depth-tested against what the opaque pass drew, it
 * covers only the pixels where no surface is. */

void main()
{
  gl_Position = vec4(pos, 1.0, 1.0);
}
