/* Front-to-back compositing of depth-peeled layers: the "under" operator (Porter & Duff 1984,
 * read front to back). The accumulator holds the premultiplied radiance C and coverage A of the
 * layers in front; this layer (straight radiance c, coverage a) adds what they let through:
 * C += (1 - A) a c, A += (1 - A) a. Over the opaque image behind, C + (1 - A) L_behind is the
 * same as blending the layers far to near (L = a c + (1 - a) L_behind, repeated).
 *
 * SL_HOLDOUT: the layers' Holdout share H too (alpha of a second colour; a layer's h <= a, the
 * part of its coverage a Holdout cuts), H += (1 - A) h: as Cycles' integrate_surface_holdout adds
 * the Holdout's weight times the path's throughput to the pixel's transparency. The renderer
 * subtracts H from the alpha of the layers over the opaque image, (A - H) + (1 - A) alpha_behind:
 * what is behind stays hidden by the whole coverage, the alpha loses the Holdout's share. */

void main()
{
  ivec2 texel = ivec2(gl_FragCoord.xy);
  vec4 acc = texelFetch(accumulated, texel, 0);
  vec4 layer = texelFetch(peeled, texel, 0);
  float through = (1.0 - acc.a) * layer.a;
  frag_color = vec4(acc.rgb + through * layer.rgb, acc.a + through);
#ifdef SL_HOLDOUT
  float held = texelFetch(accumulated_holdout, texel, 0).a;
  frag_holdout = vec4(0.0, 0.0, 0.0, held + (1.0 - acc.a) * texelFetch(peeled_holdout, texel, 0).a);
#endif
}
