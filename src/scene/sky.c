/*
 * sky.c — the analytic daylight skies of sky.h.
 *
 *   CIE overcast   Moon & Spencer 1942, CIE standard overcast sky: L(θ) = L_z (1 + 2 cos θ)/3, whose
 *                  horizontal irradiance is E_h = ∫ L cos θ dω = 7π/9 L_z.
 *   CIE clear      CIE 1973 (Kittler's formula; ISO 15469 sky type 12): L(θ, γ)/L_z = f(γ) φ(θ) / (f(Z_s) φ(0))
 *                  with f(γ) = 0.91 + 10 e^{−3γ} + 0.45 cos² γ and φ(θ) = 1 − e^{−0.32/cos θ}.
 *   Perez          Perez, Seals & Michalsky 1993 eq. 1: l(θ, γ) = (1 + a e^{b/cos θ})(1 + c e^{dγ} + e cos² γ),
 *                  a–e from the sky clearness ε and brightness Δ of Perez et al. 1990 (eqs. 1, 2) by the
 *                  1993 paper's Table 1 and eqs. 6–8; the sky is scaled so that its horizontal irradiance is
 *                  the given diffuse horizontal irradiance, as gendaylit does.
 *
 * Below the horizon the ground is a uniform Lambertian reflector of the horizontal irradiance (sky plus
 * sun): L_g = ρ_g E_h / π, as gensky's ground glow. The solar position uses the approximations of
 * Radiance's gensky (declination 0.4093 sin(2π(J − 81)/368), equation of time 0.170 sin(4π(J − 80)/373) −
 * 0.129 sin(2π(J − 8)/355) hours).
 *
 * The sun's disc (its radius, radiance and sampling) is the scene's sun light (scene.h, lights.c); here
 * only its direct normal irradiance, given or gensky's default.
 *
 * Radiance's own sky functions, which gensky and gendaylit write into a scene (ic_sky_cal), are evaluated
 * as their files define them (Radiance's skybright.cal and perezlum.cal): the same CIE and Perez formulas
 * as above, but scaled by the arguments given (a zenith brightness and gensky's normalisation A4, or
 * gendaylit's diffuse normalisation), evaluated below the horizon too, and blended into the ground
 * brightness near the horizon by the weights (Dz + 1.01)^±10; skybright.cal adds the uniform sky and the
 * CIE intermediate sky (gensky -u, -i).
 */
#include "scene/sky.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define PI_D 3.14159265358979323846

/* Perez et al. 1993, Table 1: for each clearness bin, a1…a4, b1…b4, c1…c4, d1…d4, e1…e4. */
static const double perez_table[8][20] = {
    {1.3525, -0.2576, -0.2690, -1.4366, -0.7670, 0.0007, 1.2734, -0.1233, 2.8000, 0.6004, 1.2375, 1.0000, 1.8734,
     0.6297, 0.9738, 0.2809, 0.0356, -0.1246, -0.5718, 0.9938},
    {-1.2219, -0.7730, 1.4148, 1.1016, -0.2054, 0.0367, -3.9128, 0.9156, 6.9750, 0.1774, 6.4477, -0.1239, -1.5798,
     -0.5081, -1.7812, 0.1080, 0.2624, 0.0672, -0.2190, -0.4285},
    {-1.1000, -0.2515, 0.8952, 0.0156, 0.2782, -0.1812, -4.5000, 1.1766, 24.7219, -13.0812, -37.7000, 34.8438,
     -5.0000, 1.5218, 3.9229, -2.6204, -0.0156, 0.1597, 0.4199, -0.5562},
    {-0.5484, -0.6654, -0.2672, 0.7117, 0.7234, -0.6219, -5.6812, 2.6297, 33.3389, -18.3000, -62.2500, 52.0781,
     -3.5000, 0.0016, 1.1477, 0.1062, 0.4659, -0.3296, -0.0876, -0.0329},
    {-0.6000, -0.3566, -2.5000, 2.3250, 0.2937, 0.0496, -5.6812, 1.8415, 21.0000, -4.7656, -21.5906, 7.2492, -3.5000,
     -0.1554, 1.4062, 0.3988, 0.0032, 0.0766, -0.0656, -0.1294},
    {-1.0156, -0.3670, 1.0078, 1.4051, 0.2875, -0.5328, -3.8500, 3.3750, 14.0000, -0.9999, -7.1406, 7.5469, -3.4000,
     -0.1078, -1.0750, 1.5702, -0.0672, 0.4016, 0.3017, -0.4844},
    {-1.0000, 0.0211, 0.5025, -0.5119, -0.3000, 0.1922, 0.7023, -1.6317, 19.0000, -5.0000, 1.2438, -1.9094, -4.0000,
     0.0250, 0.3844, 0.2656, 1.0468, -0.3788, -2.4517, 1.4656},
    {-1.0500, 0.0289, 0.4260, 0.3590, -0.3250, 0.1156, 0.7781, 0.0025, 31.0625, -14.5000, -46.1148, 55.3750, -7.2312,
     0.4050, 13.3500, 0.6234, 1.5000, -0.6426, 1.8564, 0.5636}};

/* Upper bounds of the clearness bins (the last is open). */
static const double clearness_bounds[7] = {1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200};

/* Solar constant (W/m²) of Perez et al. 1990's brightness Δ. */
#define SOLAR_CONSTANT 1367.0

double ic_sky_gensky_direct_normal(double alt)
{
    double sin_alt = sin(alt);
    return 6e-5 * 1.5e9 / 208.0 * (1.147 - 0.147 / (sin_alt > 0.16 ? sin_alt : 0.16));
}

int ic_sky_day_of_year(int month, int day)
{
    static const int before[12] = {0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334};
    return before[(month < 1 ? 1 : month > 12 ? 12 : month) - 1] + day;
}

void ic_sky_sun_position(int month, int day, double hour, double latitude, double longitude, double meridian,
                         double *altitude, double *azimuth)
{
    int j = ic_sky_day_of_year(month, day);
    double decl = 0.4093 * sin(2.0 * PI_D * (j - 81) / 368.0);
    /* solar time: the equation of time plus 4 minutes per degree east of the time zone's meridian */
    double solar = hour + 0.170 * sin(4.0 * PI_D * (j - 80) / 373.0) - 0.129 * sin(2.0 * PI_D * (j - 8) / 355.0) +
                   (longitude - meridian) / 15.0;
    double lat = latitude * PI_D / 180.0, h = PI_D * solar / 12.0; /* h: hour angle from midnight */
    *altitude = asin(sin(lat) * sin(decl) - cos(lat) * cos(decl) * cos(h));
    /* azimuth from south towards west, then turned to "from north towards east" */
    double from_south_west = -atan2(cos(decl) * sin(h), -cos(lat) * sin(decl) - sin(lat) * cos(decl) * cos(h));
    double az = PI_D + from_south_west;
    *azimuth = az - 2.0 * PI_D * floor(az / (2.0 * PI_D));
}

void ic_sky_perez_coefficients(double clearness, double brightness, double sun_zenith, double coef[5])
{
    int bin = 0;
    while (bin < 7 && clearness >= clearness_bounds[bin])
        ++bin;
    const double *x = perez_table[bin];
    double z = sun_zenith, delta = brightness;
    for (int i = 0; i < 5; ++i)
        coef[i] = x[4 * i] + x[4 * i + 1] * z + delta * (x[4 * i + 2] + x[4 * i + 3] * z);
    if (bin == 0) { /* the overcast bin's c and d (eqs. 7 and 8) */
        coef[2] = exp(pow(delta * (x[8] + x[9] * z), x[10])) - x[11];
        coef[3] = -exp(delta * (x[12] + x[13] * z)) + x[14] + delta * x[15];
    }
}

/* Kittler's indicatrix f(γ) and gradation φ(θ) of the CIE clear sky. */
static double clear_f(double gamma) { return 0.91 + 10.0 * exp(-3.0 * gamma) + 0.45 * cos(gamma) * cos(gamma); }
static double clear_phi(double cos_theta) { return 1.0 - exp(-0.32 / cos_theta); }

static double perez_l(const double c[5], double cos_theta, double gamma)
{
    /* cos θ is held at 0.01 or more near the horizon, where e^{b/cos θ} would blow up for b > 0 (as
     * Radiance's perezlum.cal does) */
    double ct = cos_theta < 0.01 ? 0.01 : cos_theta, cg = cos(gamma);
    return (1.0 + c[0] * exp(c[1] / ct)) * (1.0 + c[2] * exp(c[3] * gamma) + c[4] * cg * cg);
}

double ic_sky_relative(ic_sky_model model, const double coef[5], double sun_zenith, double cos_theta,
                       double cos_gamma)
{
    double gamma = acos(cos_gamma < -1.0 ? -1.0 : cos_gamma > 1.0 ? 1.0 : cos_gamma);
    switch (model) {
    case IC_SKY_CIE_OVERCAST:
        return (1.0 + 2.0 * cos_theta) / 3.0;
    case IC_SKY_CIE_CLEAR:
        return clear_f(gamma) * clear_phi(cos_theta) / (clear_f(sun_zenith) * clear_phi(1.0));
    case IC_SKY_PEREZ: {
        double l = perez_l(coef, cos_theta, gamma) / perez_l(coef, 1.0, sun_zenith);
        return l > 0.0 ? l : 0.0; /* the fit can dip below 0 for rare parameters; gendaylit clamps too */
    }
    default:
        return 0.0;
    }
}

/* ∫ relative(d) cos θ dω over the upper hemisphere, by the midpoint rule in (cos θ, φ) where the
 * integrand is smooth (the circumsolar peak spans ~0.3 rad, 50 cells). */
static double relative_horizontal(const ic_sky *s)
{
    if (s->model == IC_SKY_CIE_OVERCAST)
        return 7.0 * PI_D / 9.0;
    enum { N_MU = 512, N_PHI = 1024 };
    double sum = 0.0;
    for (int i = 0; i < N_MU; ++i) {
        double mu = (i + 0.5) / N_MU, sin_t = sqrt(1.0 - mu * mu), row = 0.0;
        for (int k = 0; k < N_PHI; ++k) {
            double phi = 2.0 * PI_D * (k + 0.5) / N_PHI;
            ic_vec3 d = v3_add(v3_scale(s->up, (float)mu),
                               v3_add(v3_scale(s->north, (float)(sin_t * cos(phi))),
                                      v3_scale(s->east, (float)(sin_t * sin(phi)))));
            row += ic_sky_relative(s->model, s->perez, s->sun_zenith, mu, (double)v3_dot(d, s->sun));
        }
        sum += row * mu;
    }
    return sum * (1.0 / N_MU) * (2.0 * PI_D / N_PHI);
}

/* Perez et al. 1990: sky clearness ε (eq. 1) and brightness Δ (eq. 2, Kasten's air mass). */
static void perez_clearness_brightness(const ic_sky_params *p, double sun_zenith, double *eps, double *delta)
{
    double z3 = 1.041 * sun_zenith * sun_zenith * sun_zenith;
    *eps = ((p->diffuse_horizontal + p->direct_normal) / p->diffuse_horizontal + z3) / (1.0 + z3);
    double zdeg = sun_zenith * 180.0 / PI_D;
    double air_mass = 1.0 / (cos(sun_zenith) + 0.15 * pow(93.885 - zdeg, -1.253));
    double ecc = 1.0;
    if (p->has_date) { /* the orbit's eccentricity correction of the extraterrestrial irradiance */
        double a = 2.0 * PI_D * (ic_sky_day_of_year(p->month, p->day) - 1) / 365.0;
        ecc = 1.00011 + 0.034221 * cos(a) + 0.00128 * sin(a) + 0.000719 * cos(2.0 * a) + 0.000077 * sin(2.0 * a);
    }
    *delta = p->diffuse_horizontal * air_mass / (SOLAR_CONSTANT * ecc);
    /* The ranges the coefficients were fitted on, as gendaylit limits them (ε in [1, 12.01], Δ in
     * [0.01, 0.6]): outside, a low sun's air mass drove Δ past 1 and the model put all the light at the
     * horizon (a vertical sensor read 140 times the diffuse horizontal irradiance), or overflowed to NaN. */
    *eps = fmin(fmax(*eps, 1.0), 12.01);
    *delta = fmin(fmax(*delta, 0.01), 0.6);
    /* gendaylit's likelihood limit: in the intermediate bins Δ below 0.2 lies outside the data the
     * coefficients were fitted on */
    if (*eps > 1.065 && *eps < 2.8 && *delta < 0.2)
        *delta = 0.2;
}

/* The sky frame from p->north (made horizontal and unit), turned by p->rotation_deg. */
static int sky_frame(ic_sky *s, const ic_sky_params *p, char *why, size_t why_size)
{
    s->up = v3(0.0f, 1.0f, 0.0f);
    ic_vec3 n = p->has_north ? p->north : v3(0.0f, 0.0f, -1.0f);
    n.y = 0.0f;
    if (!(v3_len2(n) > 1e-12f)) {
        snprintf(why, why_size, "'north' has no horizontal part; give a direction such as [0, 0, -1]");
        return 0;
    }
    s->north = v3_rotate_y(v3_norm(n), (float)p->rotation_deg);
    s->east = v3_cross(s->north, s->up);
    return 1;
}

int ic_sky_init(ic_sky *s, const ic_sky_params *p, char *why, size_t why_size)
{
    memset(s, 0, sizeof *s);
    s->model = p->model;
    if (!sky_frame(s, p, why, why_size))
        return 0;
    if (p->model != IC_SKY_CIE_OVERCAST) {
        if (p->has_sun_direction) {
            if (!(v3_len2(p->sun_direction) > 0.0f)) {
                snprintf(why, why_size, "'sun_direction' is zero; give the direction towards the sun");
                return 0;
            }
            s->sun = v3_rotate_y(v3_norm(p->sun_direction), (float)p->rotation_deg);
        } else {
            double meridian = p->has_meridian ? p->meridian : 15.0 * floor(p->longitude / 15.0 + 0.5);
            double alt, az;
            ic_sky_sun_position(p->month, p->day, p->hour, p->latitude, p->longitude, meridian, &alt, &az);
            ic_vec3 horiz = v3_add(v3_scale(s->north, (float)cos(az)), v3_scale(s->east, (float)sin(az)));
            s->sun = v3_norm(v3_add(v3_scale(horiz, (float)cos(alt)), v3_scale(s->up, (float)sin(alt))));
        }
        if (!(s->sun.y > 0.0f)) {
            snprintf(why, why_size,
                     "the sun is %s the horizon (altitude %.2f°); this sky needs daylight: choose another "
                     "time or 'cie-overcast'",
                     s->sun.y < 0.0f ? "below" : "on", asin((double)s->sun.y) * 180.0 / PI_D);
            return 0;
        }
        s->sun_zenith = acos((double)s->sun.y);
    }
    if (p->model == IC_SKY_PEREZ) {
        perez_clearness_brightness(p, s->sun_zenith, &s->clearness, &s->brightness);
        ic_sky_perez_coefficients(s->clearness, s->brightness, s->sun_zenith, s->perez);
    }
    double rel_h = relative_horizontal(s);
    if (p->diffuse_horizontal > 0.0) {
        s->horizontal = p->diffuse_horizontal;
        s->zenith_radiance = p->diffuse_horizontal / rel_h;
    } else {
        s->zenith_radiance = p->zenith_radiance;
        s->horizontal = p->zenith_radiance * rel_h;
    }
    s->direct_normal = p->direct_normal_gensky ? ic_sky_gensky_direct_normal(PI_D / 2.0 - s->sun_zenith)
                                               : p->direct_normal;
    double rho = p->has_ground ? p->ground_reflectance : 0.2;
    double sun_h = s->direct_normal * (s->model == IC_SKY_CIE_OVERCAST ? 0.0 : (double)s->sun.y);
    s->ground_radiance = rho * (s->horizontal + sun_h) / PI_D;
    return 1;
}

/* ---- Radiance's sky functions (skybright.cal, perezlum.cal) ---- */

int ic_sky_cal_init(ic_sky_cal *cal, ic_sky_function function, const double *a, size_t count, char *why,
                    size_t why_size)
{
    memset(cal, 0, sizeof *cal);
    cal->function = function;
    const int perez = function == IC_SKY_FUNCTION_PEREZLUM;
    const int type = perez || count == 0 ? 0 : (a[0] >= 1.0 && a[0] <= 4.0 && a[0] == floor(a[0])) ? (int)a[0] : -1;
    if (type < 0) {
        snprintf(why, why_size, "its first argument, the sky type, must be 1 (clear), 2 (overcast), 3 (uniform) or 4 "
                 "(intermediate)");
        return 0;
    }
    /* the overcast and uniform skies have no sun: gensky writes them 3 arguments */
    const int sunless = type == IC_SKY_TYPE_OVERCAST || type == IC_SKY_TYPE_UNIFORM;
    if (perez ? count != 10 : !(count == 7 || (sunless && count == 3))) {
        snprintf(why, why_size, "has %zu real arguments; %s", count,
                 perez  ? "perezlum.cal takes 10 (diffuse normalisation, ground brightness, Perez a b c d e, sun x y z)"
                 : sunless ? "skybright.cal takes 3 for the overcast and uniform skies (type, zenith brightness, ground "
                             "brightness) or 7"
                 : type ? "skybright.cal takes 7 for the clear and intermediate skies (type, zenith brightness, ground "
                          "brightness, normalisation, sun x y z)"
                        : "skybright.cal takes 3 (type, zenith brightness, ground brightness) or 7 (and normalisation, "
                          "sun x y z)");
        return 0;
    }
    for (size_t i = 0; i < count; ++i)
        if (!isfinite(a[i])) {
            snprintf(why, why_size, "argument A%zu is not a finite number", i + 1);
            return 0;
        }
    cal->type = type;
    cal->brightness = perez ? a[0] : a[1];
    cal->ground = perez ? a[1] : a[2];
    if (!(cal->brightness >= 0.0 && cal->ground >= 0.0)) {
        snprintf(why, why_size, "its %s (A%d) and ground brightness (A%d) must be >= 0 (given %g and %g)",
                 perez ? "diffuse normalisation" : "zenith brightness", perez ? 1 : 2, perez ? 2 : 3, cal->brightness,
                 cal->ground);
        return 0;
    }
    if (perez)
        memcpy(cal->perez, a + 2, sizeof cal->perez);
    else if (!sunless && !(a[3] > 0.0)) {
        snprintf(why, why_size, "its normalisation A4 must be > 0 (given %g)", a[3]);
        return 0;
    }
    cal->norm = perez || sunless ? 1.0 : a[3];
    if (count >= 7) {
        const double *sun = a + (perez ? 7 : 4);
        double len = sqrt(sun[0] * sun[0] + sun[1] * sun[1] + sun[2] * sun[2]);
        if (!(fabs(len - 1.0) <= 0.01)) {
            snprintf(why, why_size, "its sun direction (A%d–A%d) has length %g; give the unit vector towards the sun, "
                     "as gensky and gendaylit write it", perez ? 8 : 5, perez ? 10 : 7, len);
            return 0;
        }
        memcpy(cal->sun, sun, sizeof cal->sun); /* as given, as Radiance uses it (gensky writes 6 decimals) */
        cal->sun_zenith = acos(fmin(fmax(cal->sun[2], -1.0), 1.0));
    }
    return 1;
}

/* The sky's value above the horizon (where the ground is blended in below), as the .cal files define it. */
static double cal_sky(const ic_sky_cal *c, double dz, double cos_gamma)
{
    double cg = fmin(fmax(cos_gamma, -1.0), 1.0), gamma = acos(cg); /* Radiance's Acos clamps */
    if (c->function == IC_SKY_FUNCTION_PEREZLUM) {
        /* perezlum.cal: cos θ held at 0.01 or more, as the module's Perez sky; Exp(x) is 0 below x = −100 */
        const double *p = c->perez;
        double x = p[1] / fmax(dz, 0.01), y = p[3] * gamma;
        double gradation = 1.0 + p[0] * (x < -100.0 ? 0.0 : exp(x));
        return c->brightness * gradation * (1.0 + p[2] * (y < -100.0 ? 0.0 : exp(y)) + p[4] * cg * cg);
    }
    switch (c->type) {
    case IC_SKY_TYPE_CLEAR: /* Kittler's f(γ) and, above 0.01, φ(θ) (1 below); normalised by A4 */
        return c->brightness * clear_f(gamma) * (dz > 0.01 ? clear_phi(dz) : 1.0) / c->norm;
    case IC_SKY_TYPE_OVERCAST:
        return c->brightness * (1.0 + 2.0 * dz) / 3.0;
    case IC_SKY_TYPE_UNIFORM:
        return c->brightness;
    default: { /* the CIE intermediate sky: η the direction's zenith angle, zt the sun's */
        double eta = acos(fmin(fmax(dz, -1.0), 1.0)), zt = c->sun_zenith;
        return c->brightness * ((1.35 * sin(5.631 - 3.59 * eta) + 3.12) * sin(4.396 - 2.6 * zt) + 6.37 - eta) / 2.326 *
               exp(gamma * -0.563 * ((2.629 - eta) * (1.562 - zt) + 0.812)) / c->norm;
    }
    }
}

double ic_sky_cal_value(const ic_sky_cal *c, ic_vec3 d)
{
    if (c->function == IC_SKY_FUNCTION_CONSTANT)
        return 1.0;
    double dz = (double)d.z, cos_gamma = (double)d.x * c->sun[0] + (double)d.y * c->sun[1] + dz * c->sun[2];
    /* Both files blend the ground in by the weights (Dz + 1.01)^±10: at the horizon the sky has 55 % of the
     * weight, 5° below it 17 %, 10° below 3 %, 5° above 86 %. */
    double w_sky = pow(dz + 1.01, 10.0), w_ground = 1.0 / w_sky;
    double v = (w_sky * cal_sky(c, dz, cos_gamma) + w_ground * c->ground) / (w_sky + w_ground);
    return v > 0.0 ? v : 0.0;
}

ic_vec3 ic_sky_radiance(const ic_sky *s, ic_vec3 d)
{
    if (s->model == IC_SKY_RADIANCE) {
        for (int k = s->glow_count; k-- > 0;) /* the last source defined that holds d, as Radiance finds it */
            if ((double)v3_dot(d, s->glows[k].direction) >= s->glows[k].cos_half_angle)
                return v3_scale(s->glows[k].colour, (float)ic_sky_cal_value(&s->glows[k].cal, d));
        return v3s(0.0f);
    }
    double cos_theta = (double)v3_dot(d, s->up);
    if (cos_theta <= 0.0)
        return v3s((float)s->ground_radiance);
    return v3s((float)(s->zenith_radiance *
                       ic_sky_relative(s->model, s->perez, s->sun_zenith, cos_theta, (double)v3_dot(d, s->sun))));
}
