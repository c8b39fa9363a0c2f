/* exr_meta.c — the EXR header attributes of a render's outputs (exr_meta.h). */
#include "exr_meta.h"

#include "json_out.h"

#include "core/read_file.h"
#include "irrcache/cache.h"
#include "irrcache/version.h"

#include <cjson/cJSON.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void add(ic_cli_exr_meta *m, const char *name, const char *value)
{
    if (m->count < IC_CLI_EXR_META_MAX && value) {
        m->items[m->count].name = name;
        m->items[m->count].value = value;
        ++m->count;
    }
}

void ic_cli_exr_meta_make(const ic_cli_args *a, const ic_render_stats *st, ic_cli_exr_meta *m)
{
    memset(m, 0, sizeof *m);
    add(m, "irrcache:version", ic_version());
    /* Text attributes in UTF-8, as the JSON outputs are (OpenImageIO's Python binding, for one, fails on other
     * bytes): a byte of the scene's path that is not UTF-8 is written as U+FFFD, in :scene and :settings. */
    int oom = 0;
    m->scene = a->scene ? ic_cli_utf8_repaired(a->scene, &oom) : NULL;
    add(m, "irrcache:scene", oom ? NULL : m->scene ? m->scene : a->scene);
    /* The scene file's own bytes identify it (its meshes and textures are not hashed here). */
    char *data = NULL;
    size_t size = 0;
    if (a->scene && ic_read_regular_file(a->scene, "scene file", UINT64_MAX, "", &data, &size, NULL, NULL) == IC_OK) {
        snprintf(m->text[0], sizeof m->text[0], "%016" PRIx64, ic_fnv1a64(IC_FNV64_OFFSET, data, size));
        add(m, "irrcache:scene_fnv1a64", m->text[0]);
    }
    free(data);
    add(m, "irrcache:integrator", a->render.integrator == IC_INTEGRATOR_IC ? "ic" : "pt");
    snprintf(m->text[1], sizeof m->text[1], "%" PRIu64, st->seed);
    add(m, "irrcache:seed", m->text[1]);
    snprintf(m->text[2], sizeof m->text[2], "%d", st->spp);
    add(m, "irrcache:spp", m->text[2]);
    /* Fixed width, so that the header's size does not depend on the time. */
    snprintf(m->text[3], sizeof m->text[3], "%014.3f", st->seconds);
    add(m, "irrcache:seconds", m->text[3]);
    cJSON *settings = ic_cli_settings_json(a);
    m->settings = settings && ic_cli_json_utf8(settings) ? cJSON_PrintUnformatted(settings) : NULL;
    cJSON_Delete(settings);
    add(m, "irrcache:settings", m->settings);
    /* An interrupted render's image is partial: how much of the final render it holds. Interrupted after a
     * whole final render (during the AOVs' renders), the image is whole: the AOVs are marked (render.c). */
    if (st->cancelled && st->completed < 1.0)
        ic_cli_exr_meta_partial(m, "interrupted", st->completed);
}

void ic_cli_exr_meta_partial(ic_cli_exr_meta *m, const char *why, double completed)
{
    snprintf(m->text[4], sizeof m->text[4], "%s; %.3f of the final render", why, completed);
    add(m, "irrcache:partial", m->text[4]);
}

void ic_cli_exr_meta_free(ic_cli_exr_meta *m)
{
    free(m->settings);
    m->settings = NULL;
    cJSON_free(m->scene);
    m->scene = NULL;
}
