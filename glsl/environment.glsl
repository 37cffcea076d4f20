/* The world as a radiance field (addon/extract.py reads it, addon/environment.py is the numpy
 * twin): the constant terms' sum plus up to SL_ENV_IMAGES image terms, each its Background
 * weight times an Environment Texture looked up in a direction, exactly as Cycles does
 * (kernel/camera/projection.h, svm_node_tex_environment). */

/* Cycles' equirectangular mapping: u = (pi - atan2(y, x)) / 2pi, v = 1 - acos(z) / pi: +X at
 * the image centre, +Y a quarter to the left of it, up (+Z) along the top row. */
vec2 equirect_uv(vec3 d)
{
  float len2 = dot(d, d);
  if (len2 <= 0.0) {
    return vec2(0.0);
  }
  float u = (d.x == 0.0 && d.y == 0.0) ? 0.5 : 0.5 - atan(d.y, d.x) * (0.5 * INV_PI);
  return vec2(u, 1.0 - acos_accurate(d.z * inversesqrt(len2)) * INV_PI);
}

/* The unit direction of equirectangular coordinates: the inverse of equirect_uv. */
vec3 equirect_direction(vec2 uv)
{
  float phi = PI - 2.0 * PI * uv.x;
  float theta = PI * (1.0 - uv.y);
  return vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

/* Cycles' mirror ball: the image is a chrome ball seen along +Y from -Y (u along +X, v along +Z). */
vec2 mirror_ball_uv(vec3 d)
{
  d = normalize(d);
  d.y -= 1.0;
  float div = 2.0 * sqrt(max(-0.5 * d.y, 0.0));
  if (div > 0.0) {
    d /= div;
  }
  return 0.5 * (d.xz + 1.0);
}

/* Bilinear lookup between texel centres (Cycles' "Linear"), repeating in u (the seam of an
 * equirectangular image) and clamped in v; "Closest" takes the texel under uv. Done by hand
 * with texelFetch: textures made from Python carry no wrap setting. */
vec4 env_texel(sampler2D map, ivec2 size, int x, int y)
{
  x = x - size.x * int(floor(float(x) / float(size.x)));
  return texelFetch(map, ivec2(x, clamp(y, 0, size.y - 1)), 0);
}

vec4 env_lookup(sampler2D map, vec2 uv, bool closest)
{
  ivec2 size = textureSize(map, 0);
  vec2 p = uv * vec2(size);
  if (closest) {
    return env_texel(map, size, int(floor(p.x)), int(floor(p.y)));
  }
  p -= 0.5;
  vec2 i = floor(p);
  vec2 f = p - i;
  int x = int(i.x), y = int(i.y);
  return mix(mix(env_texel(map, size, x, y), env_texel(map, size, x + 1, y), f.x),
             mix(env_texel(map, size, x, y + 1), env_texel(map, size, x + 1, y + 1), f.x), f.y);
}

/* One image term: the world direction through the Mapping node (lookup), then the projection. */
vec3 env_term(sampler2D map, mat4 lookup, vec4 kind, vec3 d)
{
  vec3 v = (lookup * vec4(d, 1.0)).xyz;
  vec2 uv = kind.x > 0.5 ? mirror_ball_uv(v) : equirect_uv(v);
  return env_lookup(map, uv, kind.y > 0.5).rgb;
}

#ifdef SL_ENV_IMAGES
vec3 world_radiance(vec3 d)
{
  vec3 c = world.constant_radiance.rgb;
#if SL_ENV_IMAGES > 0
  c += world.weight[0].rgb * env_term(env_image_0, world.lookup[0], world.kind[0], d);
#endif
#if SL_ENV_IMAGES > 1
  c += world.weight[1].rgb * env_term(env_image_1, world.lookup[1], world.kind[1], d);
#endif
#if SL_ENV_IMAGES > 2
  c += world.weight[2].rgb * env_term(env_image_2, world.lookup[2], world.kind[2], d);
#endif
#if SL_ENV_IMAGES > 3
  c += world.weight[3].rgb * env_term(env_image_3, world.lookup[3], world.kind[3], d);
#endif
  return c;
}
#endif
