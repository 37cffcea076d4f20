/* One light's reflected radiance from its irradiance E and direction l (light_irradiance, after
 * the shadow test, whose factor is `visibility`): the body of mesh.frag.glsl's light loop, shared
 * with the term harness (tests/test_stability.py). Twin: shading.shade_light. Needs the model
 * file's shade_direct (and, for the physically based model, pbr_specular_tint). */

#ifdef SL_LTC
#  ifdef SL_SHEEN
/* The sheen's light from the polygon shade_polygon_light shaded last (its radiance times the
 * integral of the sheen's LTC over it: exact, the lobe being a linearly transformed cosine itself,
 * Zeltner et al. 2022), for shade_light to add beside the surface's; x < 0: no polygon was shaded
 * (a point, spot or sun, a light in its far field), the sheen is taken at the light's direction. */
vec3 sheen_polygon_light;
#  endif
#endif

#ifdef SL_LTC
/* A light of radiance L (rgb, as it arrives: windowed and shadowed) over a polygon of unclipped
 * form factor `form_factor` whose irradiance-weighted direction is l, on the physically based
 * model: the diffuse lobe from the polygon's irradiance cut by the horizon (the sphere of the same
 * vector form factor, ltc.glsl), the specular lobe from the linearly transformed cosine's
 * integral over the polygon (ltc_lobe_integral), with the Fresnel term at the half vector of l. */
vec3 shade_polygon_light(Surface s, LightPolygon poly, vec3 L, float form_factor, vec3 l,
                         vec4 factors, float specular_scale)
{
  if (max(L.r, max(L.g, L.b)) <= 0.0 || form_factor <= 0.0) {
    return vec3(0.0); /* behind the emitting side, shadowed, or out of reach */
  }
  float NoL = dot(s.n, l);
  vec3 c = vec3(0.0);
  if (NoL > 0.0) {
    float clipped = ltc_horizon_clip(min(form_factor, 1.0), 1.0 + NoL);
    Surface base = s;
#  ifdef SL_DIFFUSE_ROUGHNESS
    if (factors.x > 0.0) { /* none for a coat shaded as a surface of its own (its diffuse factor 0) */
      base.bsdfs.on_polygon = oren_nayar_polygon(s, poly); /* its lobe over the light (closures.glsl) */
    }
#  endif
    c = shade_direct(base, l, L * (PI * clipped / NoL), factors * vec4(1.0, 0.0, 1.0, 1.0));
  }
  float density;
#  ifdef SL_SHEEN
  sheen_polygon_light = s.sheen.color * L * (ltc_polygon_frame(s.sheen.ltc, s.sheen.n, poly, l, density) *
                                             factors.x);
#  endif
#  ifdef SL_ANISOTROPY
  /* the anisotropic lobe by its visible normals over the polygon, in closed form (anisotropy.glsl) */
  float lobe = anisotropic_polygon(s.aniso, s.n, s.v, s.NoV, poly);
#  else
  float form_factor_lobe = ltc_polygon(s, poly, l, density);
  float lobe = 0.0;
  if (form_factor_lobe > 0.0) {
    float lobe_l;
#    ifdef SL_GLOSSY
    /* Beckmann's and Ashikhmin-Shirley's ratio over the light (closures.glsl) */
    float lobe_sum, density_sum;
    if (glossy_ltc_ratio(s, poly, form_factor_lobe, lobe_sum, density_sum)) {
      lobe_l = lobe_sum;
      density = density_sum;
    }
    else {
      lobe_l = pbr_lobe(s, l);
    }
#    else
    lobe_l = pbr_lobe(s, l);
#    endif
    lobe = ltc_lobe_integral(form_factor_lobe, s.ltc.albedo, lobe_l, density);
  }
#  endif
  if (lobe > 0.0) {
    float LoH = saturate(dot(l, half_vector(l, s.v, s.n)));
    c += pbr_specular_tint(s, LoH) * L * (lobe * factors.y * specular_scale);
  }
  return c;
}

#  ifdef SL_HAS_AREA
/* An area light: its polygon of radiance I / A; behind the light, or seen from its far field, the
 * point emitter E_Area shades. */
vec3 shade_area_light(Surface s, LightData light, vec3 l, vec3 E, float visibility, vec4 factors)
{
  LightPolygon poly = area_polygon(light, s.p);
  if (area_far_field(light, dot(poly.to_centre, poly.to_centre))) {
    return shade_direct(s, l, E, factors);
  }
  /* the radiance as it arrives: the emitter's I / A, windowed and shadowed as E is, and what of
   * the light its spread lets through (E_Area's) */
  float spread = 1.0;
  float lobe_spread = 1.0;
#    ifdef SL_AREA_SPREAD
  if (light.influence.z > 0.0) {
    mat3 to_shading = transpose(mat3(s.ltc.x_axis, s.ltc.y_axis, s.n));
    spread = area_spread(light, s.p, poly, true, s.ltc.m, to_shading, lobe_spread);
  }
#    endif
  vec3 L = light.intensity_blend.rgb * (spread * visibility * light_window(light, s.p) /
                                        max(area_light_area(light), 1e-12));
  float L_max = max(L.r, max(L.g, L.b));
  float E_max = max(E.r, max(E.g, E.b));
  if (L_max <= 0.0 || E_max <= 0.0) {
    return vec3(0.0);
  }
  /* E = L pi |F| along l: the form factor's length from E */
  return shade_polygon_light(s, poly, L, E_max / (PI * L_max), l, factors,
                             spread > 0.0 ? lobe_spread / spread : 0.0);
}
#  endif

#  if defined(SL_HAS_POINT) || defined(SL_HAS_SPOT)
/* A sphere light of radius r: radiance I / (pi r^2) over its disc (sphere_polygon); E (E_Point's
 * or E_Spot's, windowed and shadowed) is L pi r^2 / (d^2 + r^2 [soft falloff]), so L is E times
 * that, with the spot's cone, window and shadow in it; the form factor r^2 / (d^2 [+ r^2]) is
 * sin^2 of the cone's half-angle, whose horizon clipping is Snyder's exactly. */
vec3 shade_sphere_light(Surface s, LightData light, vec3 l, vec3 E, vec4 factors, float k)
{
  int sides = k > SPHERE_FINE_K ? AREA_ELLIPSE_SIDES : SPHERE_COARSE_SIDES;
  LightPolygon poly = sphere_polygon(light, s.p, sides);
  float d2 = dot(poly.to_centre, poly.to_centre);
  if (d2 <= 0.0) {
    return vec3(0.0); /* at the centre: no direction to the light (E_Point's l = 0), no light */
  }
  float r2 = light.shape.x * light.shape.x;
  float falloff = d2 + light.shape.y * r2;
  vec3 L = E * (max(falloff, MIN_DIST2) / (PI * r2));
  return shade_polygon_light(s, poly, L, r2 / max(falloff, 1e-30), l, factors, 1.0);
}
#  endif
#endif

/* One light's radiance from the surface's lobes (the Principled BSDF's base, or a coat shaded as
 * a surface of its own: coat_surface). */
vec3 shade_light_surface(Surface s, LightData light, vec3 l, vec3 E, float visibility, vec4 factors)
{
#ifdef SL_LTC
#  ifdef SL_HAS_AREA
  if (int(light.position_kind.w) == LIGHT_AREA && light.shape.z > 0.0) {
    return shade_area_light(s, light, l, E, visibility, factors);
  }
#  endif
#endif
#ifdef SL_MODEL_PBR
#  ifdef SL_SPHERE_LIGHTS /* compiled only where a point or spot light has a radius: the unused
                          * branch alone costs 20 % of a many-light frame on llvmpipe */
  if (light.shape.x > 0.0) {
    /* a sphere light: by linearly transformed cosines over its disc (shade_sphere_light) where it
     * is large against the lobe, by its nearest point and the lobe widened by it where small
     * (lights.glsl's sphere_light_specular: exact as k = theta / alpha -> 0, and 4-16x cheaper),
     * blended between; and so beyond AREA_FAR_FIELD radii */
    float ltc_share = 0.0;
#    ifdef SL_LTC
    vec3 to_light = light.position_kind.xyz - s.p;
#      ifdef SL_ANISOTROPY
    /* against the anisotropic lobe's narrower axis: its disc where it is wide against either */
    float k = sphere_light_theta(light, s.p) / max(min(s.aniso.alpha_x, s.aniso.alpha_y), 1e-12);
#      else
    float k = sphere_light_theta(light, s.p) / max(s.alpha, 1e-12);
#      endif
    if (!sphere_far_field(light, dot(to_light, to_light))) {
      ltc_share = saturate((k - SPHERE_LTC_FROM) / (SPHERE_LTC_FULL - SPHERE_LTC_FROM));
    }
    vec3 c_ltc = ltc_share > 0.0 ? shade_sphere_light(s, light, l, E, factors, k) : vec3(0.0);
    if (ltc_share >= 1.0) {
      return c_ltc;
    }
#    endif
    Surface wide = s;
    float wide_weight, point_weight;
#    ifdef SL_ANISOTROPY
    vec3 r_specular = anisotropic_reflection(s); /* the stretched lobe's stand-in (anisotropy.glsl) */
#    else
    vec3 r_specular = reflect(-s.v, s.n);
#    endif
    vec3 l_specular = sphere_light_specular(light, s.p, r_specular, s.alpha, wide.alpha,
                                            wide_weight, point_weight);
#    ifdef SL_ANISOTROPY
    wide.aniso = anisotropic_widened(s.aniso, s.alpha, wide.alpha);
#    endif
    vec4 specular = factors * vec4(0.0, 1.0, 1.0, 1.0);
    vec3 c_point = shade_direct(s, l, E, factors * vec4(1.0, 0.0, 1.0, 1.0)) +
                   shade_direct(wide, l, E * wide_weight, specular) +
                   shade_direct(s, l_specular, E * point_weight, specular);
#    ifdef SL_LTC
    return mix(c_point, c_ltc, ltc_share);
#    else
    return c_point;
#    endif
  }
#  endif
#endif
  return shade_direct(s, l, E, factors);
}

/* One light's radiance: the surface's, under the Principled BSDF's upper layers where the program
 * draws them (the base times what the sheen and the coat leave it at the view; the coat's specular
 * lobe by the light's own path, weighted; the sheen's cosine lobe, a diffuse lobe in Cycles' light
 * passes, at the light's direction, or over its polygon where the surface's path shaded one). */
vec3 shade_light(Surface s, LightData light, vec3 l, vec3 E, float visibility, vec4 factors)
{
#ifdef SL_SHEEN
#  ifdef SL_LTC
  sheen_polygon_light = vec3(-1.0);
#  endif
#endif
  vec3 c = shade_light_surface(s, light, l, E, visibility, factors);
#ifdef SL_TRANSMISSION
  c += transmission_light(s, light, l, E, factors); /* from behind the surface, through it */
#endif
#ifdef SL_SHEEN
#  ifdef SL_LTC
  vec3 sheen = sheen_polygon_light.x >= 0.0 ? sheen_polygon_light : sheen_direct(s, l) * E * factors.x;
#  else
  vec3 sheen = sheen_direct(s, l) * E * factors.x;
#  endif
#endif
#ifdef SL_SUBSURFACE
  /* the subsurface's share of the base, at the light's direction, the light's size smoothing its
   * terminator (subsurface.glsl) */
  c += subsurface_direct(s, l, subsurface_light_shape(light, s.p)) * E * factors.x;
#endif
#if defined(SL_COAT) || defined(SL_SHEEN)
  c *= s.below;
#endif
#ifdef SL_COAT
  c += s.coat.weight * shade_light_surface(coat_surface(s), light, l, E, visibility,
                                           factors * vec4(0.0, 1.0, 1.0, 1.0));
#endif
#ifdef SL_SHEEN
  c += sheen;
#endif
#ifdef SL_TRANSLUCENT
  /* a closure of its own beside the Principled BSDF's layers, lit from behind (every kind of light
   * as a point) */
  c += translucent_direct(s.translucent, s.n, l) * E * factors.x;
#endif
#ifdef SL_CLOSURE_BSDFS
  /* the velvet and the toons (closures.glsl), over an area or sphere light */
  vec3 bsdfs_diffuse, bsdfs_glossy;
  closure_bsdfs_light(s, light, l, bsdfs_diffuse, bsdfs_glossy);
  c += (bsdfs_diffuse * factors.x + bsdfs_glossy * factors.y) * E;
#endif
  return c;
}
