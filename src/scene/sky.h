/*
 * sky.h — analytic daylight skies as a scene environment: the CIE standard overcast sky (Moon & Spencer
 * 1942), the CIE clear sky (CIE 1973; ISO 15469 type 12) and the Perez all-weather sky (Perez, Seals &
 * Michalsky 1993), parameterised as Radiance's gensky and gendaylit take them (zenith radiance or
 * luminance, or horizontal diffuse irradiance; the sun by date, time and place or by its direction;
 * ground reflectance below the horizon). docs/scene-format.md, "Skies", gives the formulas and units.
 *
 * The sky frame: +y is up (the environment's convention), `north` a horizontal direction (default −z),
 * east = north × up (+x by default); `rotation_deg` turns the whole sky (its north and a given sun
 * direction) about +y, right-handed as an environment map's rotation (+90° turns −z into −x).
 *
 * The sun of a clear or Perez sky is a disc of angular radius IC_SKY_SUN_RADIUS_DEG and uniform radiance
 * E_dn / (π sin² radius), so that a surface facing it receives the direct normal irradiance E_dn; the
 * scene makes it its sun light (scene_json_sky.c, lights.c). The sky's own distribution is evaluated
 * everywhere, inside the disc too (the disc adds to it, as Radiance's solar source does to its sky).
 *
 * A Radiance scene's sky is what gensky or gendaylit wrote into it: its sky function (ic_sky_cal) on the
 * distant sources whose glow it modifies (ic_sky_glow), in the file's frame (+z up), with no sky frame of
 * its own. Radiances are the scene's radiometric units, W/(m²·sr); a luminance
 * L_v (cd/m²) is L_v / 179 W/(m²·sr) of white light (the 179 lm/W convention of docs/points.md).
 */
#ifndef IC_SCENE_SKY_H
#define IC_SCENE_SKY_H

#include "core/vecmath.h"

#include <stddef.h>

/* Radiance's luminous efficacy of white light (lm/W), the one conversion between the two unit systems. */
#define IC_SKY_EFFICACY 179.0
/* The sun's mean angular radius (degrees): half its 0.533° mean apparent diameter; the disc spans
 * 2π(1 − cos 0.2665°) = 6.80e-5 sr. */
#define IC_SKY_SUN_RADIUS_DEG 0.2665

typedef enum ic_sky_model {
    IC_SKY_NONE = 0,
    IC_SKY_CIE_OVERCAST,   /* L(θ) = L_z (1 + 2 cos θ)/3 */
    IC_SKY_CIE_CLEAR,      /* L(θ, γ) = L_z f(γ) φ(θ) / (f(Z_s) φ(0)) */
    IC_SKY_PEREZ,          /* L(θ, γ) ∝ (1 + a e^{b/cos θ})(1 + c e^{dγ} + e cos² γ) */
    IC_SKY_RADIANCE        /* a Radiance scene's sky glows (ic_sky.glows): gensky's or gendaylit's output */
} ic_sky_model;

/* Radiance's sky functions, as gensky and gendaylit write them into a scene: the brightfunc `skybr` of
 * skybright.cal and `skybright` of perezlum.cal, evaluated as Radiance defines them for a direction
 * (Dx, Dy, Dz) of the scene's own frame, +z up (docs/scene-format.md, "Radiance scene files"). */
typedef enum ic_sky_function {
    IC_SKY_FUNCTION_SKYBRIGHT = 1, /* gensky: A1 the sky type, A2 the zenith brightness, A3 the ground
                                      brightness, A4 the normalisation, A5–A7 the sun direction */
    IC_SKY_FUNCTION_PEREZLUM,      /* gendaylit: A1 the diffuse normalisation, A2 the ground brightness,
                                      A3–A7 the Perez coefficients a–e, A8–A10 the sun direction */
    IC_SKY_FUNCTION_CONSTANT       /* no function: 1 everywhere (a plain source wider than the sun: its glow's
                                      radiance within its cone, as Radiance renders it) */
} ic_sky_function;

/* skybright.cal's sky types (its A1, gensky's -s/+s, -c, -u, -i/+i). */
enum { IC_SKY_TYPE_CLEAR = 1, IC_SKY_TYPE_OVERCAST, IC_SKY_TYPE_UNIFORM, IC_SKY_TYPE_INTERMEDIATE };

typedef struct ic_sky_cal {
    ic_sky_function function;
    int type;             /* skybright.cal's sky type (IC_SKY_TYPE_*) */
    double brightness;    /* skybright.cal: the zenith brightness; perezlum.cal: the diffuse normalisation */
    double ground;        /* the ground brightness */
    double norm;          /* skybright.cal's normalisation of the clear and intermediate skies */
    double perez[5];      /* perezlum.cal's a–e */
    double sun[3];        /* towards the sun (+z up), as given: of length 1 within 1 % */
    double sun_zenith;    /* acos(sun[2]) */
} ic_sky_cal;

/* A distant source whose glow a sky function modifies (gensky's "skyfunc glow sky_glow ... / sky_glow
 * source sky 0 0 4 0 0 1 180"): a direction within half its angle of `direction` sees colour × the
 * function there. */
#define IC_SKY_MAX_GLOWS 8
typedef struct ic_sky_glow {
    ic_sky_cal cal;
    ic_vec3 direction;     /* unit, the cone's axis */
    double cos_half_angle;
    ic_vec3 colour;        /* the glow's radiance, which the function multiplies */
} ic_sky_glow;

/* What a scene file gives (zero means "not given" except where noted). */
typedef struct ic_sky_params {
    ic_sky_model model;
    double zenith_radiance;    /* W/(m²·sr) (gensky -b) */
    double diffuse_horizontal; /* W/m²: the sky's irradiance on an unobstructed horizontal plane (gensky -B,
                                  gendaylit -W's second value) */
    double direct_normal;      /* W/m²: the sun's irradiance at normal incidence (0: no sun) */
    int direct_normal_gensky;  /* 1: direct_normal from the sun's altitude as gensky's default sun
                                  (ic_sky_gensky_direct_normal) */
    int has_sun_direction;
    ic_vec3 sun_direction;     /* towards the sun, world space */
    int has_date;              /* month, day, hour, latitude, longitude given */
    int month, day;            /* 1–12, 1–31 */
    double hour;               /* local standard time, decimal hours */
    double latitude;           /* degrees north */
    double longitude;          /* degrees east */
    int has_meridian;
    double meridian;           /* the time zone's standard meridian, degrees east [15° × round(longitude/15°)] */
    int has_ground;
    double ground_reflectance; /* [0.2] */
    int has_north;
    ic_vec3 north;             /* horizontal direction of north [0, 0, −1] */
    double rotation_deg;       /* the sky turned about +y (north and sun_direction with it) [0] */
} ic_sky_params;

/* A sky ready to evaluate. */
typedef struct ic_sky {
    ic_sky_model model;
    ic_vec3 up, north, east;   /* the sky frame */
    ic_vec3 sun;               /* unit direction towards the sun (clear and Perez) */
    double sun_zenith;         /* radians */
    double perez[5];           /* Perez a, b, c, d, e */
    double zenith_radiance;    /* L at the zenith, W/(m²·sr) */
    double horizontal;         /* the sky's irradiance on an unobstructed horizontal plane, W/m² */
    double ground_radiance;    /* radiance below the horizon: ρ_g (E_sky + E_sun,h) / π */
    double direct_normal;      /* the sun's normal irradiance (0: no sun) */
    double clearness, brightness; /* Perez ε and Δ (Perez et al. 1990), for the record */
    ic_sky_glow glows[IC_SKY_MAX_GLOWS]; /* IC_SKY_RADIANCE: the sky's sources, in the file's order */
    int glow_count;
} ic_sky;

/* Solar position by the approximations Radiance's gensky uses (declination, equation of time): altitude and
 * azimuth in radians, azimuth measured from north towards east. month 1–12, day 1–31, hour local standard
 * time; latitude, longitude and meridian in degrees (east positive). */
void ic_sky_sun_position(int month, int day, double hour, double latitude, double longitude, double meridian,
                         double *altitude, double *azimuth);
/* The direct normal irradiance (W/m²) of gensky's default sun at altitude alt (radians): its solar
 * radiance 1.5e9/208 (1.147 − 0.147/max(sin alt, 0.16)) W/(m²·sr) (a luminance of 1.5e9 cd/m² at high
 * sun, at 208 lm/W) over gensky's solar solid angle of 6e-5 sr. */
double ic_sky_gensky_direct_normal(double alt);
/* Day of the year (1–365, no leap day) of month/day. */
int ic_sky_day_of_year(int month, int day);

/* Relative luminance of a sky model for a direction at zenith angle θ (cos θ = cos_theta > 0) and angle γ
 * to the sun (cos γ = cos_gamma), divided by its value at the zenith. coef: the Perez coefficients (Perez
 * only); sun_zenith: Z_s. */
double ic_sky_relative(ic_sky_model model, const double coef[5], double sun_zenith, double cos_theta,
                       double cos_gamma);

/* Perez et al. 1993 coefficients a–e (Table 1; eqs. 6–8 for the overcast bin) for sky clearness ε,
 * brightness Δ and solar zenith angle sun_zenith (radians). */
void ic_sky_perez_coefficients(double clearness, double brightness, double sun_zenith, double coef[5]);

/* Fills sky from p. Returns 1, or 0 with a message in why (what is wrong and what to do; the caller
 * prefixes where). */
int ic_sky_init(ic_sky *sky, const ic_sky_params *p, char *why, size_t why_size);

/* Radiance arriving from unit direction d (pointing away from the scene), W/(m²·sr): white but for a
 * Radiance scene's glows, where the last source (in the file's order) whose cone holds d gives it, as
 * Radiance picks the distant source an escaping ray finds; none: black. */
ic_vec3 ic_sky_radiance(const ic_sky *sky, ic_vec3 d);

/* Reads a sky function's real arguments a[0..count): 1, or 0 with a message in why (what is wrong and
 * what to do; the caller prefixes where). skybright.cal takes 3 arguments for the overcast and uniform
 * skies (gensky -c, -u) or 7 (any type), perezlum.cal 10; every one finite, the brightnesses >= 0, the
 * normalisation > 0, the sun direction of length 1 within 1 % (used as given, as Radiance does). */
int ic_sky_cal_init(ic_sky_cal *cal, ic_sky_function function, const double *a, size_t count, char *why,
                    size_t why_size);
/* The function's value for unit direction d (+z up), clamped at 0 (perezlum.cal's fit can dip below). */
double ic_sky_cal_value(const ic_sky_cal *cal, ic_vec3 d);

#endif
