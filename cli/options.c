/*
 * options.c — parsing, checking and describing the options of `irrcache render`, and the own options of
 * `irrcache points` and `irrcache diff`, from their tables in options.h.
 */
#include "cli.h"
#include "options.h"

#include "json_out.h"

#include <cjson/cJSON.h>
#include <ctype.h>
#include <errno.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

typedef struct opt_def {
    const char *name, *alias;
    ic_opt_kind kind;
    size_t offset;
    double min_value, max_value;
    const char *value_name;
    double def;                /* numeric default, NAN if none */
    const char *default_text;  /* "%g" takes def */
    const char *unit;
    ic_opt_scope scope;
    const char *help;
} opt_def;

/* A row of a table whose options are members of IC_OPT_ARGS. */
#define IC_OPT_ROW(id, name, alias, kind, member, lo, hi, value, def, def_text, unit, scope, help) \
    {name, alias, kind, offsetof(IC_OPT_ARGS, member), lo, hi, value, def, def_text, unit, scope, help},
#define IC_OPT_ARGS ic_cli_args
static const opt_def options[IC_ARG_COUNT] = {IC_RENDER_OPTIONS(IC_OPT_ROW)};
#undef IC_OPT_ARGS
#define IC_OPT_ARGS ic_points_args
static const opt_def points_options[IC_POINTS_ARG_COUNT] = {IC_POINTS_OPTIONS(IC_OPT_ROW)};
#undef IC_OPT_ARGS
#define IC_OPT_ARGS ic_diff_args
static const opt_def diff_options[IC_DIFF_ARG_COUNT] = {IC_DIFF_OPTIONS(IC_OPT_ROW)};
#undef IC_OPT_ARGS
#undef IC_OPT_ROW

/* A command's table: its rows, and where its args struct keeps the values as given. */
typedef struct opt_table {
    const char *command;
    const opt_def *defs;
    int count;
    size_t size, given; /* sizeof the args struct, offsetof its given[] */
} opt_table;

static const opt_table tables[] = {
    [IC_CLI_RENDER] = {"render", options, IC_ARG_COUNT, sizeof(ic_cli_args), offsetof(ic_cli_args, given)},
    [IC_CLI_POINTS] = {"points", points_options, IC_POINTS_ARG_COUNT, sizeof(ic_points_args),
                       offsetof(ic_points_args, given)},
    [IC_CLI_DIFF] = {"diff", diff_options, IC_DIFF_ARG_COUNT, sizeof(ic_diff_args), offsetof(ic_diff_args, given)},
};

/* The command named in messages: render, or another while its options (or render's it shares) are parsed. */
static const char *err_command = "render";
#define ERR(...) (ic_cli_eprintf("irrcache %s: ", err_command), ic_cli_eprintf(__VA_ARGS__), fputc('\n', stderr), 2)

static const char *scope_prefix(ic_opt_scope s)
{
    switch (s) {
    case IC_SCOPE_IC: return "ic: ";
    case IC_SCOPE_BATCH: return "ic batch: ";
    case IC_SCOPE_LAZY: return "ic lazy: ";
    case IC_SCOPE_ADAPTIVE: return "ic adaptive: ";
    default: return "";
    }
}

/* Index of value among the names of list ("a|b|c" with sep '|'), or −1. */
static int choice_index(const char *list, char sep, const char *value, size_t len)
{
    int index = 0;
    for (const char *p = list;; ++index) {
        const char *end = strchr(p, sep);
        size_t n = end ? (size_t)(end - p) : strlen(p);
        if (n == len && !strncmp(p, value, len))
            return index;
        if (!end)
            return -1;
        p = end + 1;
    }
}

static void default_string(const opt_def *o, char *buf, size_t size)
{
    snprintf(buf, size, o->default_text, o->def); /* a text without %g ignores the number */
    if (o->unit[0] && strcmp(o->default_text, "none") && !strchr(o->default_text, ' '))
        snprintf(buf + strlen(buf), size - strlen(buf), " %s", o->unit);
}

const char *ic_cli_choice(const ic_cli_args *a, ic_arg_id id)
{
    static char names[IC_ARG_COUNT][48];
    const opt_def *o = &options[id];
    const char *v = a->given[id] ? a->given[id] : o->value_name;
    size_t n = strcspn(v, "|");
    snprintf(names[id], sizeof names[id], "%.*s", (int)n, v);
    return names[id];
}

/* The size suffixes, in order: each multiplies by 2^10 more than the one before. */
static const char size_suffix[] = "KMGT";

int ic_cli_parse_size(const char *text, uint64_t *out)
{
    if (!isdigit((unsigned char)text[0]))
        return 0;
    char *end = NULL;
    errno = 0;
    unsigned long long u = strtoull(text, &end, 10);
    if (errno)
        return 0;
    if (*end) {
        const char *s = strchr(size_suffix, toupper((unsigned char)*end));
        int shift = s && *s ? 10 * (int)(s - size_suffix + 1) : 0;
        if (!shift || end[1] || u > (~0ull >> shift))
            return 0;
        u <<= shift;
    }
    *out = (uint64_t)u;
    return 1;
}

void ic_cli_size_suffixes(double max, char *buf, size_t size)
{
    int n = 1; /* K always: every limit is above 2^10 */
    while (n < (int)sizeof size_suffix - 1 && ldexp(1.0, 10 * (n + 1)) <= max)
        ++n;
    char names[32] = "", powers[64] = "";
    for (int k = 0; k < n; ++k) {
        const char *sep = k == 0 ? "" : k == n - 1 ? " or " : ", ";
        snprintf(names + strlen(names), sizeof names - strlen(names), "%s%c", sep, size_suffix[k]);
        snprintf(powers + strlen(powers), sizeof powers - strlen(powers), "%s2^%d", sep, 10 * (k + 1));
    }
    snprintf(buf, size, "%s (either case): times %s", names, powers);
}

/* One end of a range as --help writes it: a whole number in full up to 10 digits, beyond that a power of two
 * as 2^N (the uint64 seed's 2^64 as 2^64 - 1, the largest it takes); other numbers as %g without the
 * exponent's padding (1e6, 1e-30). */
static void range_end(double v, int whole, char *buf, size_t size)
{
    int e = 0;
    if (whole && fabs(v) >= 1e10 && frexp(v, &e) == 0.5)
        snprintf(buf, size, "2^%d%s", e - 1, e - 1 == 64 ? " - 1" : ""); /* uint64's 2^64 - 1 rounds to 2^64 */
    else if (whole)
        snprintf(buf, size, "%.0f", v);
    else {
        char raw[32], *x;
        snprintf(raw, sizeof raw, "%g", v);
        if ((x = strchr(raw, 'e')) != NULL) { /* "1e+06" → "1e6", "1e-06" → "1e-6" */
            char *d = x + 1, *r = x + 1;
            if (*r == '+')
                ++r;
            else if (*r == '-')
                *d++ = *r++;
            while (*r == '0' && r[1])
                ++r;
            memmove(d, r, strlen(r) + 1);
        }
        snprintf(buf, size, "%s", raw);
    }
}

/* Stores one option's value into args (ic_cli_args for render's kinds SEED and OUTPUT). Returns 0 or 2
 * (usage error printed). */
static int store(void *args, const opt_def *o, const char *val)
{
    ic_cli_args *a = args;
    /* strtoll and strtod skip leading white space, so " -1" got past the sign check of --seed and wrapped
     * to 2^64 - 1: a value starts with what it means */
    if (val[0] == ' ' || val[0] == '\t' || val[0] == '\n' || val[0] == '\r' || val[0] == '\v' || val[0] == '\f')
        return ERR("%s '%s': a value may not start with white space", o->name, val);
    /* an empty path or name is never meant: -o '' said "unknown image format", --view '' was ignored */
    if (!val[0] && o->kind == IC_OPT_STRING)
        return ERR("%s '': the value is empty; give %s", o->name, o->value_name);
    if (!val[0] && (o->kind == IC_OPT_OUTPUT || o->kind == IC_OPT_OUT_FILE))
        return ERR("%s '': the output path is empty; give a file name such as %s", o->name,
                   o->kind == IC_OPT_OUTPUT ? "out.exr" : o->value_name);
    char *field = (char *)args + o->offset, *end = NULL;
    errno = 0;
    switch (o->kind) {
    case IC_OPT_INT:
    case IC_OPT_SEED:
    case IC_OPT_RAYS: {
        if (o->kind == IC_OPT_SEED) {
            unsigned long long u = strtoull(val, &end, 10);
            if (errno || !*val || *end || val[0] == '-')
                return ERR("%s %s: expected an integer from 0 to 2^64 - 1", o->name, val);
            *(uint64_t *)field = (uint64_t)u;
            a->render.has_seed = 1;
            return 0;
        }
        long long v = strtoll(val, &end, 10);
        if (errno || !*val || *end || v < (long long)o->min_value || v > (long long)o->max_value)
            return ERR("%s %s: expected an integer from %.0f to %.0f", o->name, val, o->min_value, o->max_value);
        if (o->kind == IC_OPT_INT) {
            *(int *)field = (int)v;
        } else {
            /* M×N strata with N ≈ π·M (Ward et al. 1988's recommendation): M = sqrt(rays/π). */
            ic_gather_opts *g = (ic_gather_opts *)field;
            int m = (int)lround(sqrt((double)v / 3.14159265358979));
            if (m < 2)
                m = 2;
            g->theta_strata = (uint32_t)m;
            g->phi_strata = (uint32_t)((v + m / 2) / m);
        }
        return 0;
    }
    case IC_OPT_SIZE:
    case IC_OPT_SIZE_INT: {
        uint64_t u = 0;
        if (!ic_cli_parse_size(val, &u) || (double)u < o->min_value || (double)u > o->max_value) {
            char suffixes[160];
            ic_cli_size_suffixes(o->max_value, suffixes, sizeof suffixes);
            return ERR("%s %s: expected a whole number from %.0f to %.0f; it may end in %s", o->name, val,
                       o->min_value, o->max_value, suffixes);
        }
        if (o->kind == IC_OPT_SIZE)
            *(uint64_t *)field = u;
        else
            *(int *)field = (int)u;
        return 0;
    }
    case IC_OPT_FLOAT:
    case IC_OPT_DOUBLE:
    case IC_OPT_FLOAT_ABOVE:
    case IC_OPT_DOUBLE_ABOVE: {
        int is_float = o->kind == IC_OPT_FLOAT || o->kind == IC_OPT_FLOAT_ABOVE,
            above = o->kind == IC_OPT_FLOAT_ABOVE || o->kind == IC_OPT_DOUBLE_ABOVE;
        const char *word = strchr(o->value_name, '|'); /* "E|auto": auto is min */
        double v = word && !strcmp(val, word + 1) ? o->min_value : strtod(val, &end);
        double as_stored = is_float ? (double)(float)v : v;
        if (errno || !*val || (end && *end) || !isfinite(v) || v > o->max_value ||
            (above ? !(as_stored > o->min_value) : v < o->min_value)) {
            char lo[32], hi[32];
            range_end(o->min_value, 0, lo, sizeof lo);
            range_end(o->max_value, 0, hi, sizeof hi);
            if (above)
                return ERR("%s %s: expected a number in (%s, %s]", o->name, val, lo, hi);
            return ERR("%s %s: expected a number from %s to %s%s%s", o->name, val, lo, hi, word ? ", or " : "",
                       word ? word + 1 : "");
        }
        if (is_float)
            *(float *)field = (float)v;
        else
            *(double *)field = v;
        return 0;
    }
    case IC_OPT_NUMBERS: /* store_numbers */
        return 0;
    case IC_OPT_NUMBER_OFF: {
        ic_switched_value *sv = (ic_switched_value *)field;
        if (!strcmp(val, "off")) {
            sv->mode = IC_CACHE_OFF;
            return 0;
        }
        double v = strtod(val, &end);
        if (errno || end == val || *end || !(v > o->min_value) || !(v <= o->max_value))
            return ERR("%s %s: give a number in (%g, %g] (default %g) or off", o->name, val, o->min_value,
                       o->max_value, o->def);
        sv->mode = IC_CACHE_ON;
        sv->value = (float)v;
        return 0;
    }
    case IC_OPT_CHOICE:
    case IC_OPT_ON_OFF: {
        int k = choice_index(o->value_name, '|', val, strlen(val));
        if (k < 0)
            return ERR("%s %s: unknown value; use one of: %s", o->name, val, o->value_name);
        if (o->kind == IC_OPT_CHOICE)
            *(int *)field = k;
        else
            *(ic_cache_switch *)field = k == 0 ? IC_CACHE_ON : IC_CACHE_OFF;
        return 0;
    }
    case IC_OPT_LIST:
        for (const char *p = val; *p;) {
            size_t n = strcspn(p, ",");
            if (choice_index(o->value_name, ',', p, n) < 0)
                return ERR("%s %s: unknown name '%.*s'; use %s", o->name, val, (int)n, p, o->value_name);
            p += n + (p[n] == ',');
        }
        *(const char **)field = val;
        return 0;
    case IC_OPT_STRING:
    case IC_OPT_OUT_FILE:
        *(const char **)field = val;
        return 0;
    case IC_OPT_OUTPUT:
        if (a->output_count == IC_CLI_MAX_OUTPUTS)
            return ERR("at most %d outputs", IC_CLI_MAX_OUTPUTS);
        a->outputs[a->output_count++] = val;
        return 0;
    case IC_OPT_FLAG:
        *(int *)field = 1;
        return 0;
    case IC_OPT_FLAG_OFF:
    case IC_OPT_FLAG_ON:
        *(ic_cache_switch *)field = o->kind == IC_OPT_FLAG_ON ? IC_CACHE_ON : IC_CACHE_OFF;
        return 0;
    case IC_OPT_HELP:
        return 0;
    }
    return 0;
}

/* The words of a NUMBERS option's VALUE: how many numbers it takes. */
static int word_count(const char *text)
{
    int n = 0;
    for (const char *p = text; *p; ++p)
        n += *p != ' ' && (p == text || p[-1] == ' ');
    return n;
}

/* A NUMBERS option at argv[*i] (its '=' at eq, or NULL): its numbers from the arguments after it into
 * args; *i moves past them. Returns 0 or 2 (usage error printed). */
static int store_numbers(void *args, const opt_def *o, int argc, char **argv, int *i, const char *eq)
{
    static const char *const counts[] = {"no", "one", "two", "three", "four", "five", "six", "seven", "eight"};
    int n = word_count(o->value_name);
    if (eq)
        return ERR("%s takes %s numbers as separate arguments: %s %s", o->name, counts[n], o->name, o->value_name);
    double *field = (double *)((char *)args + o->offset);
    for (int k = 0; k < n; ++k) {
        const char *s = *i + 1 + k < argc ? argv[*i + 1 + k] : NULL;
        char *end = NULL;
        double v = s ? strtod(s, &end) : 0.0;
        if (!s || end == s || *end || !isfinite(v) || v < o->min_value || v > o->max_value) {
            char lo[32], hi[32];
            range_end(o->min_value, 0, lo, sizeof lo);
            range_end(o->max_value, 0, hi, sizeof hi);
            return ERR("%s needs %s numbers %s, each from %s to %s; number %d is %s", o->name, counts[n],
                       o->value_name, lo, hi, k + 1, s ? s : "missing");
        }
        field[k] = v;
    }
    *i += n;
    return 0;
}

static int takes_value(ic_opt_kind k)
{
    return k != IC_OPT_FLAG && k != IC_OPT_FLAG_OFF && k != IC_OPT_FLAG_ON && k != IC_OPT_HELP;
}

/* The value of option o, written as argv[*i] (its '=' at eq, or NULL): after the '=', else the next
 * argument (*i moves past it), "" for an option that takes none. NULL after a one-line usage error. */
static const char *take_value(int argc, char **argv, int *i, const opt_def *o, const char *eq)
{
    if (takes_value(o->kind)) {
        if (eq)
            return eq + 1;
        if (*i + 1 < argc)
            return argv[++*i];
        (void)ERR("%s needs a value (%s)", o->name, o->value_name);
        return NULL;
    }
    if (eq) {
        (void)ERR("%s takes no value; drop '=%s'", o->name, eq + 1);
        return NULL;
    }
    return "";
}

static int find_option(const opt_table *t, const char *arg, size_t len)
{
    for (int i = 0; i < t->count; ++i) {
        const opt_def *o = &t->defs[i];
        if ((strlen(o->name) == len && !strncmp(arg, o->name, len)) ||
            (o->alias && strlen(o->alias) == len && !strncmp(arg, o->alias, len)))
            return i;
    }
    return -1;
}

/* What no single option can check: combinations, and the integrator an option needs. */
static int check(const ic_cli_args *a)
{
    if (!a->scene)
        return ERR("no scene given; usage: irrcache render SCENE -o OUT (see --help)");
    if (a->output_count == 0)
        return ERR("no output given; add -o out.exr (or .png, .pfm, .hdr)");
    for (int i = 0; i < a->output_count; ++i)
        if (!ic_image_is_writable_format(a->outputs[i]))
            return ERR("%s: unknown image format; use .exr, .png, .pfm or .hdr", a->outputs[i]);
    int ic = a->render.integrator == IC_INTEGRATOR_IC;
    for (int i = 0; i < IC_ARG_COUNT; ++i)
        if (a->given[i] && options[i].scope != IC_SCOPE_ALL && !ic)
            return ERR("%s is an irradiance-cache option; add --integrator ic", options[i].name);
    /* An option of one construction strategy under another did nothing, without a word. */
    static const struct {
        ic_opt_scope scope;
        ic_strategy strategy;
        const char *name;
    } strategy_scopes[] = {{IC_SCOPE_BATCH, IC_STRATEGY_BATCH, "batch"},
                           {IC_SCOPE_LAZY, IC_STRATEGY_LAZY, "lazy"},
                           {IC_SCOPE_ADAPTIVE, IC_STRATEGY_ADAPTIVE, "adaptive"}};
    for (int i = 0; ic && i < IC_ARG_COUNT; ++i)
        for (int k = 0; k < 3; ++k)
            if (a->given[i] && options[i].scope == strategy_scopes[k].scope &&
                a->render.ic.strategy != strategy_scopes[k].strategy && i != IC_ARG_RECURSIVE)
                return ERR("%s applies to --strategy %s only; drop it or add --strategy %s", options[i].name,
                           strategy_scopes[k].name, strategy_scopes[k].name);
    int adaptive_on = a->render.adaptive_sampling == IC_CACHE_ON;
    if (adaptive_on && a->render.time_budget > 0)
        return ERR("--adaptive-sampling shares out a fixed --spp; drop --time");
    if (adaptive_on && a->render.spp > 0 && a->render.spp < IC_ADAPTIVE_SAMPLING_MIN_SPP)
        return ERR("--adaptive-sampling needs --spp %d or more (a pilot pass of spp/4 first)",
                   IC_ADAPTIVE_SAMPLING_MIN_SPP);
    if (a->render.ic.recursive && a->render.ic.strategy != IC_STRATEGY_LAZY)
        return ERR("--recursive builds its levels lazily; add --strategy lazy");
    const ic_cache_params *p = &a->render.ic.cache;
    if (p->min_radius > 0 && p->max_radius > 0 && p->min_radius > p->max_radius)
        return ERR("--min-radius %g is larger than --max-radius %g", (double)p->min_radius, (double)p->max_radius);
    const ic_ic_options *o = &a->render.ic;
    /* Against the other bound's default too: --max-radius-px 1 alone had the library refuse "pixel radius
     * bounds [20, 6.67]" (px over the accuracy), with exit 1. */
    float lo = a->given[IC_ARG_MIN_RADIUS_PX] ? o->min_radius_px : IC_DEFAULT_MIN_RADIUS_PX,
          hi = a->given[IC_ARG_MAX_RADIUS_PX] ? o->max_radius_px : IC_DEFAULT_MAX_RADIUS_PX;
    if (ic && lo > 0 && hi > 0 && lo > hi)
        return ERR("--min-radius-px %g%s is larger than --max-radius-px %g%s; give both", (double)lo,
                   a->given[IC_ARG_MIN_RADIUS_PX] ? "" : " (its default)", (double)hi,
                   a->given[IC_ARG_MAX_RADIUS_PX] ? "" : " (its default)");
    if (ic && o->record_shape == IC_SHAPE_ELLIPTICAL && o->error != IC_ERROR_HESSIAN)
        return ERR("--record-shape elliptical takes its axes from the irradiance Hessian; add --error hessian");
    if (ic && o->error == IC_ERROR_HESSIAN && o->gather.method == IC_GATHER_PROGRESSIVE)
        return ERR("--error hessian needs --gather stratified or hemicube (the progressive sampler has no Hessian)");
    return 0;
}

/* Where argv[*i]'s name ends: at its '=' (*eq, for a --long option) or its end. */
static size_t name_length(const char *arg, const char **eq)
{
    *eq = arg[0] == '-' && arg[1] == '-' ? strchr(arg, '=') : NULL;
    return *eq ? (size_t)(*eq - arg) : strlen(arg);
}

/* argv[*i], row id of table t (its '=' at eq, or NULL), into args; *i moves past its value(s). Returns 0, 2
 * after the one-line usage error, or −1 − id for a help option. */
static int parse_option(const opt_table *t, int id, const char *eq, int argc, char **argv, int *i, void *args)
{
    const opt_def *o = &t->defs[id];
    const char **given = (const char **)((char *)args + t->given);
    if (o->kind == IC_OPT_NUMBERS) {
        const char *first = *i + 1 < argc ? argv[*i + 1] : NULL;
        int rc = store_numbers(args, o, argc, argv, i, eq);
        if (!rc)
            given[id] = first;
        return rc;
    }
    const char *val = take_value(argc, argv, i, o, eq);
    if (!val)
        return 2;
    if (o->kind == IC_OPT_HELP)
        return -1 - id;
    int rc = store(args, o, val);
    if (!rc)
        given[id] = val;
    return rc;
}

int ic_cli_parse(int argc, char **argv, ic_cli_args *a)
{
    memset(a, 0, sizeof *a);
    int only_positional = 0;
    for (int i = 1; i < argc; ++i) {
        const char *arg = argv[i];
        if (only_positional || arg[0] != '-' || !arg[1]) {
            if (a->scene)
                return ERR("unexpected argument '%s'; give one scene file", arg);
            a->scene = arg;
            continue;
        }
        if (!strcmp(arg, "--")) {
            only_positional = 1;
            continue;
        }
        const char *eq;
        size_t len = name_length(arg, &eq);
        int id = find_option(&tables[IC_CLI_RENDER], arg, len);
        if (id < 0)
            return ERR("%.*s: unknown option; see irrcache render --help", (int)len, arg);
        int rc = parse_option(&tables[IC_CLI_RENDER], id, eq, argc, argv, &i, a);
        if (rc)
            return rc;
    }
    return check(a);
}

int ic_cli_parse_shared_option(int argc, char **argv, int *i, ic_cli_args *a, const char *command,
                               const ic_arg_id *ids, size_t count)
{
    const char *eq;
    size_t len = name_length(argv[*i], &eq);
    int id = find_option(&tables[IC_CLI_RENDER], argv[*i], len), shared = 0;
    for (size_t k = 0; k < count; ++k)
        shared |= id == (int)ids[k];
    if (!shared)
        return 0;
    err_command = command;
    int rc = parse_option(&tables[IC_CLI_RENDER], id, eq, argc, argv, i, a);
    err_command = "render";
    return rc ? -1 : 1;
}

void ic_cli_command_defaults(ic_cli_command cmd, void *args)
{
    const opt_table *t = &tables[cmd];
    memset(args, 0, t->size);
    for (int i = 0; i < t->count; ++i) {
        const opt_def *o = &t->defs[i];
        char *field = (char *)args + o->offset;
        switch (o->kind) {
        case IC_OPT_INT:
        case IC_OPT_SIZE_INT:
            if (!isnan(o->def))
                *(int *)field = (int)o->def;
            break;
        case IC_OPT_SIZE:
            if (!isnan(o->def))
                *(uint64_t *)field = (uint64_t)o->def;
            break;
        case IC_OPT_FLOAT:
        case IC_OPT_FLOAT_ABOVE:
            if (!isnan(o->def))
                *(float *)field = (float)o->def;
            break;
        case IC_OPT_DOUBLE:
        case IC_OPT_DOUBLE_ABOVE:
            if (!isnan(o->def))
                *(double *)field = o->def;
            break;
        case IC_OPT_CHOICE: {
            int k = choice_index(o->value_name, '|', o->default_text, strlen(o->default_text));
            *(int *)field = k < 0 ? 0 : k;
            break;
        }
        default:
            break;
        }
    }
}

int ic_cli_parse_command_option(ic_cli_command cmd, int argc, char **argv, int *i, void *args)
{
    const opt_table *t = &tables[cmd];
    const char *eq;
    size_t len = name_length(argv[*i], &eq);
    err_command = t->command;
    int id = find_option(t, argv[*i], len), rc;
    if (id < 0)
        rc = ERR("%.*s: unknown option; see irrcache %s --help", (int)len, argv[*i], t->command);
    else
        rc = parse_option(t, id, eq, argc, argv, i, args);
    err_command = "render";
    return rc;
}

/* A space that wrap() prints but does not break a line at: a range ("[1, 65536]") stays on one line. */
#define GLUE '\x01'

/* Writes text from column `indent` on, wrapped at IC_CLI_HELP_COLUMNS; `at` is the current column. */
static void wrap(FILE *f, const char *text, int indent, int at)
{
    const char *p = text;
    while (*p) {
        size_t word = strcspn(p, " ");
        if (at > indent && at + 1 + (int)word > IC_CLI_HELP_COLUMNS) {
            fprintf(f, "\n%*s", indent, "");
            at = indent;
        } else if (at > indent) {
            fputc(' ', f);
            ++at;
        }
        for (size_t k = 0; k < word; ++k)
            fputc(p[k] == GLUE ? ' ' : p[k], f);
        at += (int)word;
        p += word;
        while (*p == ' ')
            ++p;
    }
    fputc('\n', f);
}

static void option_left(const opt_def *o, char *buf, size_t size, const char *quote)
{
    snprintf(buf, size, "%s%s%s%s%s%s%s%s", quote, o->alias ? o->alias : "", o->alias ? ", " : "", o->name,
             takes_value(o->kind) ? " " : "", takes_value(o->kind) ? o->value_name : "", quote, "");
}

/* A number option's declared range as --help and the README show it: "[1, 65536]", "(0, 1]" where the
 * lower end is excluded (a number or off); "" for an option that takes no number. `space` follows the
 * comma and in "2^64 - 1" (GLUE for wrap()). */
static void range_text(const opt_def *o, char space, char *buf, size_t size)
{
    char lo[32], hi[32];
    int whole = o->kind == IC_OPT_INT || o->kind == IC_OPT_SEED || o->kind == IC_OPT_SIZE ||
                o->kind == IC_OPT_SIZE_INT || o->kind == IC_OPT_RAYS;
    int open = o->kind == IC_OPT_NUMBER_OFF || o->kind == IC_OPT_FLOAT_ABOVE || o->kind == IC_OPT_DOUBLE_ABOVE;
    buf[0] = 0;
    if (!whole && !open && o->kind != IC_OPT_FLOAT && o->kind != IC_OPT_DOUBLE && o->kind != IC_OPT_NUMBERS)
        return;
    range_end(o->min_value, whole, lo, sizeof lo);
    range_end(o->max_value, whole, hi, sizeof hi);
    snprintf(buf, size, "%c%s, %s]", open ? '(' : '[', lo, hi);
    for (char *p = buf; *p; ++p)
        *p = *p == ' ' ? space : *p;
}

/* An option's help as --help and the README give it: its text, and for a size or count its suffixes. */
static void help_text(const opt_def *o, char *buf, size_t size)
{
    snprintf(buf, size, "%s", o->help);
    if (o->kind == IC_OPT_SIZE || o->kind == IC_OPT_SIZE_INT) {
        char suffixes[160];
        ic_cli_size_suffixes(o->max_value, suffixes, sizeof suffixes);
        snprintf(buf + strlen(buf), size - strlen(buf), "; %s may end in %s", o->value_name, suffixes);
    }
}

static void print_row(FILE *f, const opt_def *o, int left_width)
{
    char left[96], help[2048], text[2400], def[96], range[80];
    option_left(o, left, sizeof left, "");
    default_string(o, def, sizeof def);
    help_text(o, help, sizeof help);
    range_text(o, GLUE, range, sizeof range);
    snprintf(text, sizeof text, "%s%s%s%s%s%s%s", scope_prefix(o->scope), help, range[0] ? " " : "", range,
             def[0] ? " [default: " : "", def, def[0] ? "]" : "");
    int at = fprintf(f, "  %-*s", left_width - 2, left);
    if (2 + (int)strlen(left) >= left_width) { /* no room for a space before the help: it starts below */
        fputc('\n', f);
        fprintf(f, "%*s", left_width, "");
        at = left_width;
    }
    wrap(f, text, left_width, at);
}

void ic_cli_print_option(FILE *f, ic_arg_id id, int left_width)
{
    print_row(f, &options[id], left_width);
}

void ic_cli_print_option_default(FILE *f, ic_arg_id id, double value, int left_width)
{
    opt_def o = options[id];
    o.def = value;
    o.default_text = "%g";
    print_row(f, &o, left_width);
}

void ic_cli_print_command_options(FILE *f, ic_cli_command cmd, int left_width)
{
    for (int i = 0; i < tables[cmd].count; ++i)
        print_row(f, &tables[cmd].defs[i], left_width);
}

void ic_cli_print_help(FILE *f)
{
    fprintf(f, "usage: irrcache render SCENE -o OUT [options]\n\n"
               "SCENE is a JSON scene file (docs/scene-format.md) or a mesh (.obj .gltf .glb .ply,\n"
               "each also gzip-compressed: .obj.gz).\n"
               "Options take their value as --name VALUE or --name=VALUE; -- ends the options.\n\n"
               "options:\n");
    ic_cli_print_command_options(f, IC_CLI_RENDER, 30);
    fprintf(f, "\nexit status: 0 success, 1 failure while working (I/O, malformed scene), 2 usage error, 3 the render\n"
               "finished but an output could not be written (each such output named; the others written), 130 or 143\n"
               "interrupted by SIGINT or SIGTERM: the render stops at its next tile and every output holds the\n"
               "image so far, marked partial (EXR attribute irrcache:partial, \"interrupted\" in --stats; one that\n"
               "could not be written is named as for 3, the status still 130 or 143). During\n"
               "cache construction no new gather begins (a pass stops within a few records), and the records made\n"
               "so far render one sample per pixel (a preview; where no record reaches, one path-traced ray). A\n"
               "second signal ends it at once.\n"
               "progress line (stderr a terminal): the phase and its share done, the render's elapsed time and\n"
               "the time left of the whole render (construction, final render, AOVs); shown as '-' during cache\n"
               "construction without --time, whose length depends on when the cache converges\n");
}

/* A table cell cannot hold a bare '|'. */
static void md_cell(FILE *f, const char *text)
{
    for (const char *p = text; *p; ++p) {
        if (*p == '|')
            fputc('\\', f);
        fputc(*p, f);
    }
}

/* The rows of table t (of render's: the irradiance-cache options, or the others) but its help options. */
static void markdown_table(FILE *f, const opt_table *t, int ic)
{
    fprintf(f, "| option | range | default | meaning |\n|---|---|---|---|\n");
    for (int i = 0; i < t->count; ++i) {
        const opt_def *o = &t->defs[i];
        if ((o->scope != IC_SCOPE_ALL) != ic || o->kind == IC_OPT_HELP)
            continue;
        char left[96], def[96], help[2048], range[80];
        option_left(o, left, sizeof left, "`");
        default_string(o, def, sizeof def);
        help_text(o, help, sizeof help);
        range_text(o, ' ', range, sizeof range);
        fputs("| ", f);
        md_cell(f, left);
        fputs(" | ", f);
        md_cell(f, range);
        fputs(" | ", f);
        md_cell(f, def);
        fputs(" | ", f);
        const char *prefix = scope_prefix(o->scope);
        if (ic && strcmp(prefix, "ic: "))
            fprintf(f, "%.*s: ", (int)strlen(prefix) - 5, prefix + 3);
        md_cell(f, help);
        fputs(" |\n", f);
    }
}

void ic_cli_print_markdown(FILE *f)
{
    fprintf(f, "Common options:\n\n");
    markdown_table(f, &tables[IC_CLI_RENDER], 0);
    fprintf(f, "\nIrradiance caching (`--integrator ic`):\n\n");
    markdown_table(f, &tables[IC_CLI_RENDER], 1);
}

void ic_cli_print_command_markdown(FILE *f, ic_cli_command cmd)
{
    markdown_table(f, &tables[cmd], 0);
}

void ic_cli_option_markdown(ic_arg_id id, char *buf, size_t size)
{
    option_left(&options[id], buf, size, "`");
}

/* "--max-radius-px" → "max_radius_px". */
static void json_key(const char *name, char *buf, size_t size)
{
    snprintf(buf, size, "%s", name + 2);
    for (char *p = buf; *p; ++p)
        if (*p == '-')
            *p = '_';
}

/* A float default as written (0.01, not 0.0099999998). */
static cJSON *default_number(const opt_def *o)
{
    /* %g: a float default as written (0.15, not 0.150000006); a whole number in full (2^26, not 6.71089e7) */
    char buf[32];
    double d = (double)o->def;
    snprintf(buf, sizeof buf, d == floor(d) && fabs(d) < 9007199254740992.0 ? "%.0f" : "%g", d);
    return cJSON_CreateNumber(strtod(buf, NULL));
}

static cJSON *setting(const ic_cli_args *a, int id)
{
    const opt_def *o = &options[id];
    const char *given = a->given[id];
    switch (o->kind) {
    case IC_OPT_FLAG:
    case IC_OPT_FLAG_OFF:
    case IC_OPT_FLAG_ON:
        return cJSON_CreateBool(given != NULL);
    case IC_OPT_CHOICE:
    case IC_OPT_ON_OFF:
        if (!given && o->kind == IC_OPT_ON_OFF)
            return cJSON_CreateString(o->default_text);
        return cJSON_CreateString(ic_cli_choice(a, (ic_arg_id)id));
    case IC_OPT_SEED:
        if (given)
            return ic_cli_json_u64(a->render.seed); /* the parsed value, exact ("007" is no JSON number) */
        break;
    case IC_OPT_SIZE:
        if (given)
            return cJSON_CreateNumber((double)*(const uint64_t *)((const char *)a + o->offset)); /* "64M" parsed */
        break;
    case IC_OPT_SIZE_INT:
        if (given)
            return cJSON_CreateNumber(*(const int *)((const char *)a + o->offset));
        break;
    case IC_OPT_INT:
    case IC_OPT_FLOAT:
    case IC_OPT_DOUBLE:
    case IC_OPT_FLOAT_ABOVE:
    case IC_OPT_DOUBLE_ABOVE:
    case IC_OPT_RAYS:
        if (given)
            return cJSON_CreateNumber(strtod(given, NULL));
        break;
    case IC_OPT_NUMBER_OFF:
        if (given)
            return strcmp(given, "off") ? cJSON_CreateNumber(strtod(given, NULL)) : cJSON_CreateString("off");
        break;
    case IC_OPT_STRING:
    case IC_OPT_OUT_FILE:
    case IC_OPT_LIST:
        return given ? cJSON_CreateString(given) : cJSON_CreateNull();
    case IC_OPT_NUMBERS: /* not in render's table */
    case IC_OPT_OUTPUT:
    case IC_OPT_HELP:
        return NULL;
    }
    if (!isnan(o->def))
        return default_number(o);
    return strcmp(o->default_text, "none") ? cJSON_CreateString(o->default_text) : cJSON_CreateNull();
}

cJSON *ic_cli_settings_json(const ic_cli_args *a)
{
    cJSON *obj = cJSON_CreateObject();
    for (int i = 0; i < IC_ARG_COUNT; ++i) {
        cJSON *v = setting(a, i);
        if (!v)
            continue;
        char key[64];
        json_key(options[i].name, key, sizeof key);
        cJSON_AddItemToObject(obj, key, v);
    }
    return obj;
}
