/*
 * radiance_view.c — the camera of a Radiance view file: its lines that start with rview, rpict or rvu (a
 * command line) or with VIEW= (a picture header), whose view options (Larson & Shakespeare 1998) apply in order:
 *
 *   -vt the view type: v perspective, l parallel, h hemispherical fisheye, a angular fisheye, c cylindrical
 *   panorama, s planisphere (stereographic fisheye); -vp eye, -vd direction, -vu up, -vh and -vv the full
 *   horizontal and vertical view sizes (degrees; world units for a parallel view), -vs and -vl the view
 *   shift and lift (the image plane moved by these fractions of its width and height), -vo the fore
 *   clipping distance (rays start that far out), -va the aft clipping distance (warned about and
 *   ignored); -vf (a view from another file) is refused.
 *
 * Other options on those lines (rpict's -x, -ab, ...) are skipped. Radiance's defaults stand for what the
 * file leaves out: -vp 0 0 0 -vd 0 1 0 -vu 0 0 1 -vh 45 -vv 45. As rpict does, the image is the largest that
 * fits the requested width × height with square pixels: the dimension the view's aspect does not fill shrinks
 * (the aspect is that of the image plane: ic_projection_extent). A perspective view keeps -vv and takes its
 * horizontal angle from that image's aspect, as irrcache's pinhole camera always has.
 */
#include "scene/radiance_internal.h"

#include "core/error_at.h"
#include "core/read_file.h"
#include "irrcache/defaults.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct view {
    ic_vec3 vp, vd, vu;
    double vh, vv, vs, vl, vo, va;
    char type;
} view;

/* The view types, their projections and the largest sizes Radiance accepts for them (degrees; is_open:
 * the size must stay below it, as the projection's plane runs to infinity there). */
static const struct {
    char type;
    ic_projection projection;
    double max_size;
    int is_open;
    const char *what;
} types[] = {
    {'v', IC_PROJECTION_PERSPECTIVE, 180.0, 1, "perspective"},
    {'l', IC_PROJECTION_PARALLEL, INFINITY, 1, "parallel"},
    {'h', IC_PROJECTION_HEMISPHERICAL, 180.0, 0, "hemispherical fisheye"},
    {'a', IC_PROJECTION_ANGULAR, 360.0, 0, "angular fisheye"},
    {'c', IC_PROJECTION_CYLINDRICAL, 360.0, 0, "cylindrical panorama"},
    {'s', IC_PROJECTION_STEREOGRAPHIC, 360.0, 1, "planisphere"},
};
enum { TYPE_COUNT = sizeof types / sizeof types[0] };

static int type_index(char t)
{
    for (int k = 0; k < TYPE_COUNT; ++k)
        if (types[k].type == t)
            return k;
    return -1;
}

static int numbers(char **words, int count, int at, int n, double *out)
{
    if (at + n > count)
        return 0;
    for (int i = 0; i < n; ++i) {
        char *end;
        out[i] = strtod(words[at + i], &end);
        if (*end || end == words[at + i] || !isfinite(out[i]))
            return 0;
    }
    return 1;
}

/* Applies the view options among words[from..count) to v. */
static ic_result options(const char *path, int line, char **words, int count, int from, view *v, ic_error *err)
{
    for (int i = from; i < count; ++i) {
        const char *o = words[i];
        if (o[0] != '-' || o[1] != 'v') /* another program option or its value */
            continue;
        double x[3];
        const char *opt = o + 2;
        if (opt[0] == 't') {
            if (opt[1] && !opt[2] && type_index(opt[1]) >= 0) {
                v->type = opt[1];
                continue;
            }
            return ic_error_set_at(err, IC_ERR_PARSE, path, line,
                                   "unknown view type '%s'; the types are -vtv (perspective), -vtl (parallel), -vth "
                                   "and -vta (hemispherical and angular fisheye), -vtc (cylindrical) and -vts "
                                   "(planisphere)",
                                   o);
        }
        int n3 = !strcmp(opt, "p") || !strcmp(opt, "d") || !strcmp(opt, "u");
        int n1 = !strcmp(opt, "h") || !strcmp(opt, "v") || !strcmp(opt, "s") || !strcmp(opt, "l") ||
                 !strcmp(opt, "o") || !strcmp(opt, "a");
        if (!strcmp(opt, "f"))
            return ic_error_set_at(err, IC_ERR_UNSUPPORTED, path, line,
                                   "-vf (a view read from another file) is not followed; put that view's options in "
                                   "this file");
        if (!n3 && !n1)
            return ic_error_set_at(err, IC_ERR_PARSE, path, line,
                                   "unknown view option '%s'; the view options are -vt -vp -vd -vu -vh -vv -vs -vl -vo "
                                   "-va",
                                   o);
        if (!numbers(words, count, i + 1, n3 ? 3 : 1, x))
            return ic_error_set_at(err, IC_ERR_PARSE, path, line, "%s needs %d number%s after it", o, n3 ? 3 : 1,
                                   n3 ? "s" : "");
        i += n3 ? 3 : 1;
        ic_vec3 vec = v3((float)x[0], (float)x[1], (float)x[2]);
        switch (opt[0]) {
        case 'p': v->vp = vec; break;
        case 'd': v->vd = vec; break;
        case 'u': v->vu = vec; break;
        case 'h': v->vh = x[0]; break;
        case 'v': v->vv = x[0]; break;
        case 's': v->vs = x[0]; break;
        case 'l': v->vl = x[0]; break;
        case 'o': v->vo = x[0]; break;
        default: v->va = x[0]; break;
        }
    }
    return IC_OK;
}

ic_result ic_rad_read_view(const char *path, const ic_scene_load_options *opt, ic_scene *scene, ic_error *err)
{
    char *text = NULL;
    size_t len = 0;
    ic_result r = ic_read_regular_file(path, "view file", 1u << 20, "a view file is a few lines of options", &text, &len,
                                       NULL, err);
    if (r != IC_OK)
        return r;
    view v = {v3s(0.0f), v3(0.0f, 1.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), 45.0, 45.0, 0.0, 0.0, 0.0, 0.0, 'v'};
    int found = 0, line = 0, last_line = 0;
    char *words[256];
    for (char *s = text + ic_utf8_bom_length(text, len), *next; r == IC_OK && s && s < text + len; s = next) {
        ++line;
        next = memchr(s, '\n', (size_t)(text + len - s));
        if (next)
            *next++ = '\0';
        int count = 0;
        for (char *w = s; *w && count < 256;) { /* split at white space, in place */
            while (*w && strchr(" \t\r\f\v", *w))
                *w++ = '\0';
            if (*w)
                words[count++] = w;
            while (*w && !strchr(" \t\r\f\v", *w))
                ++w;
        }
        if (count == 0)
            continue;
        const char *prog = strrchr(words[0], '/') ? strrchr(words[0], '/') + 1 : words[0];
        int from;
        if (!strcmp(prog, "rview") || !strcmp(prog, "rpict") || !strcmp(prog, "rvu") || !strcmp(words[0], "VIEW="))
            from = 1;
        else if (!strncmp(words[0], "VIEW=", 5)) /* "VIEW=-vtv ..." */
            words[0] += 5, from = 0;
        else
            continue;
        found = 1;
        last_line = line;
        r = options(path, line, words, count, from, &v, err);
    }
    free(text);
    if (r != IC_OK)
        return r;
    if (!found)
        return ic_error_set(err, IC_ERR_PARSE,
                            "%s: no view in it; a view file has a line starting with rview, rpict or VIEW= followed by "
                            "view options (-vp x y z -vd x y z ...)",
                            path);
    ic_vec3 side = v3_cross(v.vd, v.vu);
    if (!(v3_len2(v.vd) > 0.0f) || !(v3_len2(side) > 1e-12f * v3_len2(v.vd) * v3_len2(v.vu)))
        return ic_error_set_at(err, IC_ERR_INVALID_ARG, path, last_line,
                               "the view direction (-vd) must be non-zero and not parallel to the up vector (-vu)");
    const int k = type_index(v.type);
    const double max = types[k].max_size;
    if (!(v.vh > 0.0 && v.vv > 0.0 &&
          (types[k].is_open ? v.vh < max && v.vv < max : v.vh <= max && v.vv <= max)))
        return ic_error_set_at(err, IC_ERR_INVALID_ARG, path, last_line,
                               "-vh and -vv must be in (0, %g%s for a %s view (given %g and %g)", max,
                               types[k].is_open ? ")" : "]", types[k].what, v.vh, v.vv);
    if (types[k].projection == IC_PROJECTION_CYLINDRICAL && !(v.vv < 180.0))
        return ic_error_set_at(err, IC_ERR_INVALID_ARG, path, last_line,
                               "-vv must be below 180 degrees for a cylindrical view (perspective up; given %g)", v.vv);
    if (!(fabs(v.vs) <= 100.0 && fabs(v.vl) <= 100.0))
        return ic_error_set_at(err, IC_ERR_INVALID_ARG, path, last_line,
                               "-vs and -vl are fractions of the image's width and height; give them within "
                               "[-100, 100] (given %g and %g)",
                               v.vs, v.vl);
    if (!(v.vo >= 0.0))
        return ic_error_set_at(err, IC_ERR_INVALID_ARG, path, last_line,
                               "the fore clipping distance -vo must be >= 0 (given %g)", v.vo);
    if (v.va != 0.0)
        ic_scene_warn(scene, "%s:%d: the aft clipping distance -va is ignored: everything beyond the fore plane is seen",
                      path, last_line);
    double aspect = ic_projection_extent(types[k].projection, v.vh, 1) / /* width / height */
                    ic_projection_extent(types[k].projection, v.vv, 0);
    int w = opt->width > 0 ? opt->width : IC_DEFAULT_WIDTH, h = opt->height > 0 ? opt->height : IC_DEFAULT_HEIGHT;
    if ((double)w / h > aspect)
        w = (int)fmax(1.0, floor(h * aspect + 0.5));
    else
        h = (int)fmax(1.0, floor(w / aspect + 0.5));
    ic_camera *cam = &scene->camera;
    cam->eye = v.vp;
    cam->target = v3_add(v.vp, v3_norm(v.vd));
    cam->up = v3_norm(v.vu);
    cam->fov_y_deg = (float)v.vv;
    cam->width = w;
    cam->height = h;
    cam->projection = types[k].projection;
    cam->size_x = (float)v.vh;
    cam->size_y = (float)v.vv;
    cam->shift = (float)v.vs;
    cam->lift = (float)v.vl;
    cam->clip_near = (float)v.vo;
    return IC_OK;
}
