/* One light loop for every model: the model file bound at compile time supplies shade_direct,
 * shade_ambient and shade_finish. */

vec3 view_direction(vec3 p)
{
  if (frame.camera_position.w > 0.5) {
    return normalize(frame.camera_position.xyz - p);
  }
  return -frame.camera_forward.xyz; /* orthographic: parallel view rays */
}

/* Interpolated corner normals can be zero (a zero-length custom normal, or opposite normals
 * averaged across a triangle); fall back to the flat face normal from screen derivatives. */
vec3 shading_normal(vec3 p)
{
  float len2 = dot(world_normal, world_normal);
  if (len2 > 1e-20) {
    return world_normal * inversesqrt(len2);
  }
  vec3 face = cross(dFdx(p), dFdy(p));
  float flen2 = dot(face, face);
  return flen2 > 0.0 ? face * inversesqrt(flen2) : vec3(0.0, 0.0, 1.0);
}

void main()
{
  Surface s;
  s.p = world_position;
  s.v = view_direction(s.p);
  vec3 n = shading_normal(s.p);
  /* Back faces are shaded with the normal flipped towards the viewer, as Cycles does. */
  s.n = gl_FrontFacing ? n : -n;
  s.NoV = max(dot(s.n, s.v), MIN_COS);
  s.base_color = material.base_color.rgb;
  s.diffuse_color = material.diffuse_color.rgb;
  s.specular_color = material.specular_color.rgb;
  s.ambient_color = material.ambient_color.rgb;
  s.roughness = max(material.params.x, MIN_PERCEPTUAL_ROUGHNESS);
  s.alpha = s.roughness * s.roughness;
  s.metalness = material.params.y;
  s.shininess = material.params.z;
  s.f0_dielectric = material.params.w;
  s.f0 = mix(vec3(s.f0_dielectric), s.base_color, s.metalness);
  s.f90 = material.fresnel.x >= 0.0 ? material.fresnel.x : saturate(50.0 * dot(s.f0, vec3(1.0 / 3.0)));
  s.fresnel_p = material.fresnel.y;
  float sqrt_f0 = sqrt(min(s.f0_dielectric, 0.99));
  s.eta = (1.0 + sqrt_f0) / (1.0 - sqrt_f0);
  s.has_complex_ior = material.fresnel.z > 0.5;
  s.ior_n = material.ior_n.rgb;
  s.ior_k = material.ior_k.rgb;

  vec3 c = shade_ambient(s, frame.ambient.rgb);
  int count = int(frame.counts.x);
  for (int i = 0; i < SL_MAX_LIGHTS; i++) {
    if (i >= count) {
      break;
    }
    LightData light = lights.light[i];
    vec3 l;
    vec3 E = light_irradiance(light, s.p, l);
    c += shade_direct(s, l, E, light.factors);
  }
  frag_color = vec4(shade_finish(c), 1.0);
}
