/* Uniform-buffer layouts (std140: every member is a vec4 or mat4, so the numpy packers in
 * addon/plan/programs.py can write them as flat float32 arrays without padding rules). Lights and
 * materials live in uniform buffers because push constants are capped at 128 bytes. */

struct FrameData {
  mat4 view_proj;
  vec4 camera_position;  /* xyz: camera origin in world space; w: 1 perspective, 0 orthographic */
  vec4 camera_forward;   /* xyz: unit view axis (camera -Z) in world space */
  vec4 ambient;          /* rgb: Blinn-Phong/Phong ambient constant x (eq. 1.4) */
  vec4 counts;           /* x: number of lights in use; light culling: y the tiles' side in pixels,
                          * z tiles per row, w where the light indices start in light_tiles */
  vec4 group_ends[2];    /* where each group of lights ends (addon/plan/programs.py's light_order lists
                          * them by group): [0] those with a shadow map, [1] those without, each
                          * x point, y spot, z sun, w area lights */
  mat4 view;             /* the camera's view matrix (world -> camera space) */
  vec4 viewport;         /* xy: the target's size in pixels; z: the camera's clip start; w: the target's
                          * pixels per image pixel along an axis (supersampling's n, else 1) */
};

struct LightData {
  vec4 position_kind;    /* xyz: position; w: LIGHT_POINT / LIGHT_SPOT / LIGHT_SUN / LIGHT_AREA */
  vec4 direction_cone;   /* xyz: unit direction the light faces (its -Z); w: cos(spot_size / 2) */
  vec4 intensity_blend;  /* rgb: W/sr (point, spot, area) or W/m^2 (sun); w: spot smoothstep scale */
  vec4 factors;          /* x: diffuse factor; y: specular factor; z: 1 a sun split off the world;
                          * w: the first shadow-map layer (-1: casts no shadow) */
  vec4 shape;            /* x: a point or spot light's radius r (0: a true point); y: 1 soft falloff
                          * (Cycles' disc facing the point: E = I / (d^2 + r^2)), 0 a sphere;
                          * zw: an area light's half width and height (m) */
  vec4 area;             /* xyz: an area light's local X axis; w: 1 disk or ellipse, 0 rectangle */
  vec4 influence;        /* x: 1 / r^2 of the distance r the light reaches (0: everywhere); an area
                          * light's spread: y tan(h), z 1 / (tan h - h), h half its angle (z = 0:
                          * 180 degrees, none) */
};

/* Each light is LIGHT_TEXELS vec4 in LightData's order (mesh.frag.glsl's load_light_reach and
 * load_light_rest): up to 512 lights, where a uniform block of 64 KiB holds them (SL_LIGHT_BLOCK,
 * addon/plan/programs.py's light_block_fits), the block's texels light after light; more, the rows of a
 * texture, light_data, a light's texels in its row. With light culling (SL_LIGHT_TILES,
 * addon/plan/light_tiles.py), light_tiles holds each screen tile's (first, count) and then the tiles'
 * light indices, SL_LIGHT_LIST_WIDTH texels per row. */
#define LIGHT_TEXELS 7

#ifdef SL_LIGHT_BLOCK
struct LightBlock {
  vec4 texels[SL_MAX_LIGHTS * LIGHT_TEXELS];
};
#endif

#ifdef SL_GRAPH
/* A compiled node graph's constants (addon/materials/codegen.py's GRAPH_CONST), one block per
 * material: editing a value uploads them, the program stays. */
struct GraphBlock {
  vec4 constants[SL_GRAPH_CONSTANTS];
};
#endif

struct MaterialData {
  vec4 base_color;       /* rgb: PBR base colour */
  vec4 diffuse_color;    /* rgb: Blinn-Phong/Phong diffuse colour */
  vec4 specular_color;   /* rgb: Blinn-Phong/Phong specular colour */
  vec4 ambient_color;    /* rgb: Blinn-Phong/Phong ambient colour */
  vec4 params;           /* x: perceptual roughness r; y: metalness; z: shininess; w: dielectric F0 */
  vec4 fresnel;          /* x: F90 (< 0: automatic); y: eq. 1.13's p; z: 1 if ior_n/ior_k are set */
  vec4 ior_n;            /* rgb: conductor IOR, real part; w: a node graph's Physical Conductors' share of
                          * the metal lobe (the Principled set's exact conductor Fresnel, SL_SPECULAR_TINT) */
  vec4 ior_k;            /* rgb: conductor IOR, imaginary part (extinction) */
  vec4 emission;         /* rgb: emitted radiance (Principled Emission Color x Strength);
                          * w: alpha (coverage, 1 opaque) */
  /* The Principled BSDF's lobes beyond its base (glsl/principled.glsl; read by the physically based
   * model's Principled set where the program holds the lobe: SL_SPECULAR_TINT, SL_COAT, SL_SHEEN) */
  vec4 specular_tint;    /* rgb: Specular Tint (the dielectric F0's tint, the metal's F82 edge tint) */
  vec4 coat;             /* x: Coat Weight, y: Coat Roughness, z: Coat IOR */
  vec4 coat_tint;        /* rgb: Coat Tint (the base's colour through the coat at normal incidence) */
  vec4 sheen;            /* rgb: Sheen Weight x Sheen Tint; w: Sheen Roughness */
  vec4 coat_normal;      /* xyz: the coat's normal where a node graph gives it one (0: the surface's) */
  vec4 thin_film;        /* x: Thin Film Thickness (nm), y: Thin Film IOR, z, w: 0 (SL_THIN_FILM; the
                          * rule of the Blender that read it: SL_THIN_FILM_CYCLES_4 or none) */
  vec4 anisotropy;       /* xyz: the anisotropic lobe's tangent (world space, any length; 0: none);
                          * w: its roughness stretch k (glsl/anisotropy.glsl; 1: isotropic) */
  vec4 translucent;      /* rgb: a node graph's Translucent BSDFs' colour (SL_TRANSLUCENT) */
  vec4 subsurface;       /* rgb: the subsurface's mean free path per channel (m); w: Subsurface Weight
                          * (SL_SUBSURFACE, glsl/subsurface.glsl) */
  /* transmission (glsl/transmission.glsl, SL_TRANSMISSION) */
  vec4 transmission;     /* x: the glass share of the non-metallic part; y: 1 the Fresnel splits reflection
                          * and transmission (0: all transmitted); z: its IOR */
  vec4 transmission_tint; /* rgb: the tint of each crossing of the surface */
  vec4 reflection_tint;  /* rgb: the dielectric reflection's tint (the Glass BSDF's Color) */
  /* The closure nodes beside the Principled BSDF (glsl/closures.glsl; a node graph's, per fragment:
   * graph_surface.glsl's apply_closure_bsdfs) */
  vec4 closure_bsdfs;    /* x: the share of the sheen layered over the base (1: the Principled BSDF's;
                          * 0: a Sheen BSDF's), y: the Diffuse BSDF's Roughness (Oren-Nayar),
                          * z: the velvet's sigma, w: the share of the diffuse base beside the
                          * specular layer, not under it (EEVEE's Specular BSDF) */
  vec4 velvet;           /* rgb: Sheen BSDF (Ashikhmin) colour */
  vec4 toon_diffuse;     /* rgb: Toon BSDF (Diffuse) colour, w: its Size */
  vec4 toon_glossy;      /* rgb: Toon BSDF (Glossy) colour, w: its Size */
  vec4 toon_smooth;      /* x: the Diffuse component's Smooth, y: the Glossy's */
  vec4 diffuse_ms;       /* rgb: the Diffuse BSDF's Oren-Nayar multiple scattering, Color x E_ms */
  vec4 glossy;           /* the metal lobe's shares of a constant Fresnel (x) and uncompensated (y), the
                          * specular lobe's of Beckmann (z) and Ashikhmin-Shirley (w) (Glossy BSDF) */
  vec4 subsurface_walk;  /* the subsurface's random walk (glsl/subsurface.glsl): x Anisotropy, y the entry's
                          * IOR (0: Christensen-Burley, no walk), z its GGX alpha, w the diffuse entry's share */
};

#ifdef REFRACTION_LEVELS
/* What the glass reads of the opaque scene behind it (glsl/transmission.glsl, addon/frame/passes.py's
 * RefractionPass): the camera's clip -> world, the rectangles (x, y, width, height in texels) of the
 * copy's levels in refraction_behind (level 0 the target's size, its alpha the depth; each next half
 * the size, blurred); info: x the number of levels, yz the texture's size, w how far (m, along the
 * view) behind an opaque surface a ray still meets it; world: x the alpha where the world is behind
 * (0 with a transparent film). */
struct RefractionData {
  mat4 inverse_view_projection;
  vec4 rect[REFRACTION_LEVELS];
  vec4 info;
  vec4 world;
};
#endif

/* The world's light, precomputed (glsl/ibl.glsl, addon/reference/environment.py): nine SH coefficients
 * premultiplied by the cosine kernel's band factors, the rectangles in the atlas (x, y, width,
 * height in texels) of the prefiltered levels and, last, of the irradiance map; info.x: the
 * number of prefiltered levels, info.y: the first level made from the world with its suns split
 * off (the smoother ones keep them: info.x when there are none), info.zw: the atlas' size (each
 * rectangle has a border of one texel around it); the radiance of a world without images. (Each
 * level's roughness is glsl/ibl.glsl's env_level_roughness.) */
struct EnvironmentData {
  vec4 sh[9];
  vec4 rect[8];
  vec4 info;
  vec4 uniform_radiance;
};

struct ObjectData {
  mat4 model;
  mat4 normal_matrix;    /* inverse transpose of the model matrix's upper 3x3; [3][3]: the sign
                          * of its determinant (-1: mirrored) */
};

/* Every object's data in blocks of SL_OBJECT_BLOCK, uploaded when a matrix changes; a draw names
 * its entry with the object_index push constant. (Push constants, beside it: object_index, and
 * lobes = x: diffuse, y: specular, z: ambient weight; w: 1 applies the model's final clamp
 * (Combined), 0 leaves a light pass raw.) */
struct ObjectBlock {
  ObjectData object[SL_OBJECT_BLOCK];
};

#ifdef SL_SHADOWS
/* The frame's shadow-map layers (addon/plan/shadows.py's ShadowPlan): world -> clip, the layer's view
 * -> world, and its projection's half extents (extent.xy: tan of half the field of view, or the
 * half widths in m); info.x:
 * far distance (m per unit of stored depth), y: a texel's width per metre of distance
 * (perspective) or in metres (orthographic), z: the light's size for penumbrae (radius in m; a
 * sun's tan(angle / 2)); origin.xyz: the light's position (perspective) or the near plane's
 * centre (orthographic), w: the layer's kind (0 cube face, 1 perspective, 2 orthographic);
 * fit (orthographic): the near plane's centre e along the view's right, up and forward axes
 * (r.e, u.e, f.e), which place a point's coordinates across a sun's cascades (each cascade has
 * the sun's rotation). A light's first layer is its LightData.factors.w (-1: no shadow). */
struct ShadowBlock {
  mat4 layer_matrix[SL_SHADOW_LAYERS];
  mat4 layer_view_inverse[SL_SHADOW_LAYERS];
  vec4 layer_info[SL_SHADOW_LAYERS];
  vec4 layer_origin[SL_SHADOW_LAYERS];
  vec4 layer_extent[SL_SHADOW_LAYERS];
  vec4 layer_fit[SL_SHADOW_LAYERS];
};
#endif
