/*
 * scene.h — the renderer's scene: one flattened triangle soup, materials, lights, camera, settings.
 *
 * Loaded from a JSON scene file (scene_json.c, cJSON), a Mitsuba or Radiance scene file (mitsuba_scene.c,
 * radiance_scene.c) or a bare mesh (.obj .gltf .glb .ply, through assimp in mesh_import.c). Instances are flattened at load: every triangle lives in world space in
 * the arrays below, so the accelerator (src/geom) builds one Embree geometry and a hit's primitive
 * id indexes these arrays directly. Read-only once loaded; shared by all threads.
 *
 * Lights: emissive triangles (material with non-zero `emission`), point lights, a directional sun
 * and an environment (constant radiance, an equirectangular image or an analytic daylight sky, sky.h).
 * Light sampling: lights.c.
 */
#ifndef IC_SCENE_SCENE_H
#define IC_SCENE_SCENE_H

#include "core/microfacet.h"
#include "core/vecmath.h"
#include "scene/sky.h"
#include "irrcache/common.h"
#include "irrcache/image.h"
#include "irrcache/render.h"

#include <stdint.h>

/* Texture: linear RGB texels, repeat wrap, bilinear. A texture whose every value is the linearisation of
 * an 8-bit sRGB value (8-bit PNG and JPEG files) keeps those bytes and a table of their 256 values: the
 * same texels bit for bit in a quarter of the memory, so fewer cache misses. Others keep floats. */
typedef struct ic_texture {
    char path[1024];       /* resolved path, for messages */
    int is_data;           /* 1: values as stored (roughness, metallic, normal maps), not colours: an 8-bit or
                              16-bit file's values are v/255 (v/65535) without the sRGB curve */
    int width, height;
    float *rgb;            /* width*height*3 floats, or NULL when srgb8 holds the texels */
    uint8_t *srgb8;        /* width*height*3 sRGB bytes, or NULL */
    float linear[256];     /* with srgb8: the linear value of each byte */
} ic_texture;

/* Texel value i (0 ≤ i < width*height*3). */
static inline float ic_texture_value(const ic_texture *t, size_t i)
{
    return t->srgb8 ? t->linear[t->srgb8[i]] : t->rgb[i];
}

typedef enum ic_material_type {
    IC_MAT_DIFFUSE = 0,    /* Lambertian: kd (× texture) */
    IC_MAT_GLOSSY,         /* Lambertian kd + normalized modified Phong lobe ks, exponent ns */
    IC_MAT_MIRROR,         /* ideal specular reflection, tint ks */
    IC_MAT_GLASS,          /* dielectric: Fresnel-weighted ideal reflection/refraction, index ior */
    IC_MAT_CONDUCTOR,      /* rough metal: GGX lobe of roughness alpha; Fresnel of the complex index
                              eta + i·k when k is non-zero, else Schlick's from the colour ks = F0 (× texture) */
    IC_MAT_PLASTIC,        /* rough plastic: GGX dielectric coat (index ior, roughness alpha, tint ks) over
                              a Lambertian base kd (× texture), coupled as Kelemen & Szirmay-Kalos 2001 */
    IC_MAT_ROUGH_GLASS,    /* rough dielectric: GGX reflection and refraction (Walter et al. 2007), index
                              ior, roughness alpha; traced like glass (no light sampling through it) */
    IC_MAT_THIN_GLASS,     /* thin pane (Radiance's glass): two parallel faces of index ior a negligible
                              distance apart, ks the transmissivity of one pass through the sheet at normal
                              incidence; ideal reflection and straight-through transmission, each summed over
                              the inter-reflections in the sheet; traced like glass */
    IC_MAT_TRANSLUCENT     /* thin diffusing sheet (Radiance's trans): Lambertian reflection kd on either
                              side, Lambertian transmission kt to the other side, and straight-through
                              transmission kt_specular */
} ic_material_type;

typedef struct ic_material {
    char name[128];
    ic_material_type type;
    ic_vec3 kd;            /* diffuse albedo (linear RGB) */
    int32_t kd_texture;    /* index into scene.textures, or -1 */
    ic_vec3 ks;            /* specular albedo (glossy lobe or mirror tint; thin glass: transmissivity) */
    float ns;              /* Phong exponent (glossy) */
    ic_vec3 emission;      /* emitted radiance (one-sided, along the geometric normal's side the
                              triangle's winding gives; see `two_sided_emission`) */
    int two_sided_emission;/* 1: emits from both sides */
    int emission_cone;     /* 1: emits only towards directions within the cone below (Radiance's spotlight) */
    ic_vec3 emission_axis; /* the cone's unit axis, the direction the light points to */
    float emission_cos_cone; /* cos of the cone's half angle: a direction d from the surface gets the emission
                              when d · emission_axis ≥ it, else nothing (a hard edge, as Radiance's spotout) */
    float ior;             /* index of refraction (glass, plastic's coat), default 1.5 */
    float alpha;           /* GGX roughness α of conductor, plastic and rough glass (glTF's roughness squared) */
    ic_vec3 eta, k;        /* conductor: complex index of refraction (k all 0: use ks as F0) */
    ic_vec3 kt, kt_specular; /* translucent: diffuse and straight-through transmittance */
    float coat_albedo[IC_COAT_TABLE]; /* plastic: the coat's directional albedo E(μ), filled at load */
    float coat_albedo_avg; /* plastic: its cosine-weighted mean */
    /* textures of the microfacet parameters and the shading normal (scene_query.c), each 1 + the index
     * into scene.textures and 0 for none, so that a zeroed material has none: */
    float metallic;        /* plastic: blend towards a Schlick conductor of F0 = kd (glTF's metallic), 0..1 */
    int32_t roughness_texture; /* its green channel g scales the roughness: α = alpha·g² (glTF's rule), or
                              with roughness_is_alpha its luminance y is α itself: α = alpha·y (Mitsuba's) */
    int roughness_is_alpha;
    int32_t metallic_texture;  /* its blue channel b scales metallic: metallic·b (plastic only) */
    int32_t normal_texture;    /* tangent-space normal map (+x along u, +y along v, +z the shading normal) */
    float normal_scale;    /* glTF's normalTexture.scale: the map's x and y are multiplied by it */
    float *coat_albedo_rough; /* plastic with a roughness texture: IC_COAT_ROUGH_STEPS tables of
                              IC_COAT_TABLE + 1 floats (E(μ) then its mean) at roughness j/(steps−1);
                              owned by the scene, filled at load */
} ic_material;

/* 1 when material m emits towards unit direction d (from its surface): inside its emission cone, or it has none. */
static inline int ic_material_emits_towards(const ic_material *m, ic_vec3 d)
{
    return !m->emission_cone || v3_dot(d, m->emission_axis) >= m->emission_cos_cone;
}

/* Roughness steps of a textured plastic's coat tables (the nearest is used). */
#define IC_COAT_ROUGH_STEPS 32

/* Emissive triangle as a light. */
typedef struct ic_tri_light {
    uint32_t triangle;     /* index into scene.triangles */
    float area;
    float power;           /* pi * area * luminance(emission) (× 2 if two-sided): selection weight */
    ic_vec3 centroid, normal; /* for local selection (ic_scene_local_lights) */
    float radius;          /* largest centroid-to-vertex distance */
    int two_sided;
} ic_tri_light;

typedef struct ic_point_light {
    ic_vec3 position;
    ic_vec3 intensity;     /* W/sr per channel (radiant intensity) */
} ic_point_light;

/* A spot light's cone (KHR_lights_punctual): the intensity is scaled by t² with
 * t = clamp((cos θ − cos_outer)/(cos_inner − cos_outer), 0, 1), θ the angle from the axis. */
typedef struct ic_spot_cone {
    ic_vec3 axis;          /* unit direction the spot points to */
    float cos_inner, cos_outer; /* full intensity inside the inner cone, none outside the outer */
} ic_spot_cone;

/* The cone's factor on the intensity towards unit direction d (from the light). */
static inline float ic_spot_falloff(const ic_spot_cone *c, ic_vec3 d)
{
    float w = c->cos_inner - c->cos_outer;
    float t = w > 0.0f ? (v3_dot(c->axis, d) - c->cos_outer) / w : (v3_dot(c->axis, d) >= c->cos_outer ? 1.0f : 0.0f);
    t = ic_clampf(t, 0.0f, 1.0f);
    return t * t;
}

/* The sun: a directional light, or a disc of uniform radiance when angular_radius > 0 (a sky's sun). */
typedef struct ic_sun_light {
    int enabled;
    ic_vec3 direction;     /* unit vector from the scene towards the sun (the disc's centre) */
    ic_vec3 irradiance;    /* irradiance on a surface facing the sun (RGB) */
    float angular_radius;  /* radians; 0: a directional (delta) light */
    /* the disc, filled by ic_scene_build_lights when angular_radius > 0: */
    float one_minus_cos;   /* 1 − cos(angular_radius) */
    float solid_angle;     /* 2π (1 − cos angular_radius), sr */
    ic_vec3 radiance;      /* irradiance / (π sin² angular_radius): a surface facing the sun receives
                              exactly `irradiance` from it */
    ic_frame frame;        /* about `direction`, for sampling the disc */
} ic_sun_light;

/* A portal: a parallelogram opening (a window) through which the interior sees the environment. Light
 * sampling of the environment then picks points on the portals instead of directions on the sphere, and
 * the cache's hemisphere gathers take the light through them by the same sampling (docs/scene-format.md,
 * "Portals"). */
#define IC_MAX_PORTALS 256 /* a scene's most portals (each light sample and pdf looks at every one) */
typedef struct ic_portal {
    ic_vec3 corner;        /* one corner; the opening is corner + a edge1 + b edge2, a, b in [0, 1] */
    ic_vec3 edge1, edge2;
    ic_vec3 normal;        /* unit, edge1 × edge2 normalised: it points into the interior */
    float area;
    int rectangle;         /* edges at right angles: sampled by solid angle (portals.c), else by area */
    /* The rectangle's frame, which every point that samples it shares (portals.c): the edges' lengths
     * and unit directions, and their cross product. */
    double len1, len2;
    ic_vec3 unit1, unit2, unit_normal;
} ic_portal;

typedef struct ic_environment {
    int enabled;
    ic_vec3 radiance;      /* constant radiance, or a multiplier on the image */
    ic_image image;        /* equirectangular lat-long map (width 0 if constant); +y is up,
                              u = 0.5 + atan2(d.x, -d.z)/(2 pi), v = acos(d.y)/pi */
    float rotation_deg;    /* rotation about +y */
    /* importance sampling of the image (filled at load when image.width > 0) */
    float *marginal_cdf;   /* height+1 */
    float *conditional_cdf;/* height*(width+1) */
    float total_weight;    /* sum over texels of lum * sin(theta) */
    ic_sky sky;            /* an analytic daylight sky (model != IC_SKY_NONE): it gives the radiance, and
                              `image` holds it tabulated only for importance sampling (lights.c) */
    ic_portal *portals;    /* NULL: none, the environment is sampled over the whole sphere */
    uint32_t portal_count;
    float portal_area;     /* their total area (filled by ic_scene_build_lights) */
} ic_environment;

/* Probability with which ic_scene_sample_light picks each class of light; they sum to 1 (all 0 when
 * the scene has no light). Proportional to each class's estimated power (lights.c, docs/scene-format.md). */
typedef struct ic_light_selection {
    float tri, point, sun, env;    /* probabilities of the light classes */
    const float *tri_cdf;  /* NULL: emitting triangles by power; else a local distribution over them
                              (tri_light_count + 1 entries, from ic_scene_local_lights) */
    const float *tri_pmf;  /* its probabilities (tri_light_count entries) */
} ic_light_selection;

/* How the image maps to directions (Radiance's view types, Larson & Shakespeare 1998; film.c gives the
 * formulas). Zero is the pinhole every scene format has. */
typedef enum ic_projection {
    IC_PROJECTION_PERSPECTIVE = 0, /* pinhole: fov_y_deg, the horizontal angle from the image's aspect */
    IC_PROJECTION_PARALLEL,        /* orthographic: size_x × size_y world units */
    IC_PROJECTION_HEMISPHERICAL,   /* fisheye, orthographic onto the view hemisphere (radius ∝ sin θ) */
    IC_PROJECTION_ANGULAR,         /* fisheye, equidistant (radius ∝ θ) */
    IC_PROJECTION_CYLINDRICAL,     /* panorama: angle across, perspective up */
    IC_PROJECTION_STEREOGRAPHIC    /* planisphere fisheye (radius ∝ tan θ/2) */
} ic_projection;

typedef struct ic_camera {
    ic_vec3 eye, target, up;
    float fov_y_deg;       /* vertical full angle (horizontal fov is converted at load) */
    int width, height;     /* image resolution */
    ic_projection projection; /* 0: perspective */
    float size_x, size_y;  /* the other projections: full horizontal and vertical view size, in degrees
                              (parallel: world units) */
    float shift, lift;     /* the image plane moved right and up by these fractions of its width and
                              height (Radiance -vs, -vl); 0: centred on the view direction */
    float clip_near;       /* rays start this far out (Radiance -vo: measured along the view axis for
                              perspective, parallel and cylindrical, along the ray for the fisheyes); 0: none */
    int is_mirrored;       /* 1: the image is mirrored left to right (its right is forward × up's opposite), as
                              a mirroring camera-to-world transform makes it (Mitsuba's <scale x="-1"/>) */
} ic_camera;

/* The image-plane extent of a view size under projection p (Radiance's |hvec| or |vvec|; scene.c): what
 * the centred image coordinate in [-1/2, 1/2] is multiplied by before the projection's formula (film.c).
 * size is in degrees (parallel: world units); is_horizontal matters for the cylinder only. The ratio of
 * the horizontal to the vertical extent is the aspect of the view's square-pixel image. */
double ic_projection_extent(ic_projection p, double size, int is_horizontal);

/* Render settings a scene file may give; 0 means "not given" (the CLI or defaults decide). */
typedef struct ic_scene_settings {
    int spp;
    int max_depth;
    uint64_t seed;
    float exposure;
    int has_exposure;
} ic_scene_settings;

struct ic_scene {
    char path[1024];       /* the file it was loaded from */
    /* geometry, world space */
    ic_vec3 *positions;    /* vertex_count */
    ic_vec3 *normals;      /* vertex_count, unit shading normals, or NULL (flat shading) */
    float *uvs;            /* vertex_count*2, or NULL */
    uint32_t vertex_count;
    uint32_t *triangles;   /* triangle_count*3 vertex indices */
    uint32_t *triangle_material; /* triangle_count material indices */
    uint32_t triangle_count;
    ic_vec3 bounds_min, bounds_max;
    float ray_offset_floor; /* smallest move of a ray's origin off a surface (ic_offset_ray_origin_floor):
                              IC_RAY_OFFSET_FLOOR, times the largest coordinate of the geometry when that is
                              below 1, so that a small scene renders as its scaled-up copy does */
    /* appearance */
    ic_material *materials;
    uint32_t material_count;
    ic_texture *textures;
    uint32_t texture_count;
    float *tangents;       /* vertex_count*4: unit tangent and the bitangent's sign (w = ±1), or NULL; a zero
                              tangent means "from the triangle's texture coordinates" (scene_query.c) */
    int has_normal_maps;   /* 1 if any material has a normal_texture (ic_scene_surface looks only then) */
    uint32_t dropped_degenerate; /* zero-area triangles dropped at load (not an error) */
    /* lights */
    ic_tri_light *tri_lights;
    float *tri_light_cdf;  /* tri_light_count+1, by power */
    uint32_t tri_light_count;
    int32_t *triangle_light; /* triangle_count: index into tri_lights, or -1 */
    float tri_light_power; /* sum of tri_lights[].power */
    ic_point_light *point_lights;
    float *point_light_cdf;/* point_light_count+1, by power 4 pi lum(intensity) */
    uint32_t point_light_count;
    ic_spot_cone *point_spots; /* point_light_count cones, or NULL when no point light is a spot (the others
                              then have cos_outer = -2: no falloff) */
    ic_sun_light sun;
    ic_environment env;
    ic_light_selection light_select; /* fixed light-class probabilities (lights.c) */
    /* view and settings */
    ic_camera camera;
    ic_scene_settings settings;
    char *warnings;        /* what loading approximated or left out, lines; NULL if nothing */
    char **files;          /* the real path of every file loading read (ic_scene_file), each once */
    uint32_t file_count;
    int files_lost;        /* 1 if a path could not be kept (out of memory): the list is incomplete */
};

/* Loading (ic_scene_load, ic_scene_load_options, ic_scene_free) is declared in irrcache/render.h. */

/* --- queries used by integrators (scene_query.c / lights.c) --- */

/* Surface attributes at barycentrics (u, v) of triangle tri (b0 = 1-u-v on vertex 0, u on v1, v on v2,
 * as Embree reports them). */
/* The smallest move of a ray's origin off a surface in a scene of unit size or more (geom/accel.h:
 * ic_offset_ray_origin_floor). */
#define IC_RAY_OFFSET_FLOOR (1.0f / 65536.0f)

typedef struct ic_surface {
    ic_vec3 p;             /* position */
    ic_vec3 ng;            /* unit geometric normal (winding order) */
    ic_vec3 ns;            /* unit shading normal (= ng if no normals), flipped to ng's side */
    ic_vec3 ns_smooth;     /* ns before a normal map (the interpolated normal; = ns without a map) */
    float uv[2];           /* texture coordinates (0 if none) */
    uint32_t material;
    uint32_t triangle;
    float offset_floor;    /* the scene's ray_offset_floor (0: IC_RAY_OFFSET_FLOOR), for rays leaving here */
} ic_surface;

/* Fills s for triangle tri at barycentrics (u, v); a normal-mapped material's ns is the mapped normal. */
void ic_scene_surface(const ic_scene *scene, uint32_t tri, float u, float v, ic_surface *s);
/* GGX α and metallic of the material at a surface: the factors times their textures (without a texture,
 * alpha and metallic themselves). */
void ic_scene_microfacet_params(const ic_scene *scene, const ic_surface *s, float *alpha, float *metallic);
/* The coat albedo table (IC_COAT_TABLE values) of a plastic at a point of GGX α, and its mean. */
const float *ic_scene_coat_table(const ic_material *m, float alpha, float *average);
/* Diffuse albedo at a surface (kd × texture). */
ic_vec3 ic_scene_albedo(const ic_scene *scene, const ic_surface *s);
/* The material's texture value at a surface (1 without a texture): kd's factor, and a conductor's F0's. */
ic_vec3 ic_scene_texture_tint(const ic_scene *scene, const ic_surface *s);
/* Emitted radiance leaving surface s towards direction wo (unit, pointing away from the surface). */
ic_vec3 ic_scene_emission(const ic_scene *scene, const ic_surface *s, ic_vec3 wo);
/* Environment radiance arriving from direction d (unit, pointing away from the scene); 0 if none. */
ic_vec3 ic_scene_env_radiance(const ic_scene *scene, ic_vec3 d);

/* A light sample as seen from a shading point. */
typedef struct ic_light_sample {
    ic_vec3 wi;            /* unit direction from the point towards the light */
    float dist;            /* distance to the light point (INFINITY for sun/environment) */
    ic_vec3 radiance;      /* emitted radiance along -wi (area/env/sun disc), or intensity/dist^2 for
                              points, or irradiance for a directional sun: the integrand numerator */
    float pdf;             /* solid-angle pdf including light selection; 0 = failed sample */
    int is_delta;          /* point or directional sun: no MIS with BSDF sampling */
} ic_light_sample;

/* Samples one light for point p (u0 chooses the light, u1,u2 the point on it). */
int ic_scene_sample_light(const ic_scene *scene, ic_vec3 p, float u0, float u1, float u2, ic_light_sample *ls);
/* Solid-angle pdf with which ic_scene_sample_light would pick the point on emissive triangle tri seen from
 * p along wi at distance dist (for MIS when a BSDF-sampled ray hits an emitter). */
float ic_scene_light_pdf_triangle(const ic_scene *scene, ic_vec3 p, uint32_t tri, ic_vec3 wi, float dist);
/* The same two functions with class probabilities of the caller's choice instead of scene->light_select
 * (e.g. an integrator that handles the sun or the environment another way sets those classes to 0
 * and renormalises the rest). */
int ic_scene_sample_light_sel(const ic_scene *scene, const ic_light_selection *sel, ic_vec3 p, float u0, float u1,
                              float u2, ic_light_sample *ls);
float ic_scene_light_pdf_triangle_sel(const ic_scene *scene, const ic_light_selection *sel, ic_vec3 p, uint32_t tri,
                                      ic_vec3 wi, float dist);
/* Most emitting triangles for which a local distribution is built per pixel (above: by power only). */
#define IC_LOCAL_LIGHTS_MAX 4096
/* A distribution over the emitting triangles for receivers at p facing n: each triangle's power times
 * bounds of the two cosines over distance², mixed 3:1 with the base distribution base_pmf (NULL: by
 * power) so that every emitter keeps a probability (estimates stay unbiased for any receiver that uses
 * it); emitters the base gives probability 0 get 0. Fills pmf (tri_light_count entries) and cdf
 * (tri_light_count + 1); returns 0 if the scene has no emitting triangles, more than
 * IC_LOCAL_LIGHTS_MAX, or none the base samples. */
int ic_scene_local_lights(const ic_scene *scene, ic_vec3 p, ic_vec3 n, const float *base_pmf, float *pmf, float *cdf);
/* Solid-angle pdf of sampling the environment in direction wi (for MIS when a ray escapes). */
float ic_scene_light_pdf_env(const ic_scene *scene, ic_vec3 wi);
/* The same with portals taken into account: the solid-angle pdf of environment light sampling from p
 * (from a point inside a portal, 0 along a direction through no portal). */
float ic_scene_light_pdf_env_at(const ic_scene *scene, ic_vec3 p, ic_vec3 wi);
/* The same as if the environment were the only light (a selection whose env class has probability 1). */
float ic_scene_env_pdf_at(const ic_scene *scene, ic_vec3 p, ic_vec3 wi);
/* Portals (portals.c). A direction from p through a portal: u0 picks one of the portals p is inside of,
 * by the solid angle it subtends at p, and (u1, u2) a direction uniform in that solid angle (a rectangle)
 * or a point uniform over its area (another parallelogram); *q is the point on the portal and *pdf the
 * solid-angle pdf of the direction, summed over every portal it leaves through (ic_scene_portal_pdf).
 * Returns 0 without portals, when p is inside of none, or for an opening seen edge-on. */
int ic_scene_sample_portal(const ic_scene *scene, ic_vec3 p, float u0, float u1, float u2, ic_vec3 *wi, ic_vec3 *q,
                           float *pdf);
/* The solid-angle pdf of ic_scene_sample_portal picking direction wi (unit) from p: 0 if the ray leaves
 * through no portal (the portals p is inside of). */
float ic_scene_portal_pdf(const ic_scene *scene, ic_vec3 p, ic_vec3 wi);
/* 1 if p is on the interior side of some portal: its sky is sampled through the portals. */
int ic_scene_portals_apply(const ic_scene *scene, ic_vec3 p);
/* Distance along wi from p to the nearest portal it leaves through; INFINITY if none. */
float ic_scene_portal_crossing(const ic_scene *scene, ic_vec3 p, ic_vec3 wi);
/* The sun's disc as seen along wi (unit, pointing away from the scene): its radiance, 0 outside it or for
 * a directional sun; an escaping ray adds it to the environment's (MIS-weighted where light sampling could
 * have found it). */
ic_vec3 ic_scene_sun_radiance(const ic_scene *scene, ic_vec3 wi);
/* Solid-angle pdf of the disc's own sampling, 1/solid_angle inside it (0 outside or directional). */
float ic_scene_sun_disc_pdf(const ic_scene *scene, ic_vec3 wi);
/* The pdf with which ic_scene_sample_light_sel(sel) picks direction wi on the sun's disc: sel->sun times
 * the disc's. */
float ic_scene_light_pdf_sun(const ic_scene *scene, const ic_light_selection *sel, ic_vec3 wi);
/* Samples the sun alone (no class selection in pdf): a uniform direction on its disc (u1, u2), or its
 * direction with pdf 1 and is_delta set for a directional sun. Returns 0 without a sun. */
int ic_scene_sample_sun(const ic_scene *scene, float u1, float u2, ic_light_sample *ls);

#endif
