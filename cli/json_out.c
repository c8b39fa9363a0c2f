/* json_out.c — writing JSON files atomically (json_out.h). */
#include "json_out.h"

#include "core/atomic_file.h"

#include <stdio.h>
#include <stdlib.h>

int ic_cli_write_json(const char *cmd, const char *path, cJSON *root, int pretty)
{
    char *text = !root ? NULL : pretty ? cJSON_Print(root) : cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    if (!text) {
        fprintf(stderr, "irrcache %s: out of memory writing %s\n", cmd, path ? path : "JSON");
        return 0;
    }
    int ok = 1;
    if (!path) {
        ok = puts(text) >= 0;
    } else {
        ic_atomic_file f;
        ic_error err;
        if (ic_atomic_file_open(&f, path, &err) != IC_OK) {
            fprintf(stderr, "irrcache %s: %s\n", cmd, err.message);
            ok = 0;
        } else {
            fputs(text, f.fp);
            fputc('\n', f.fp);
            if (ic_atomic_file_commit(&f, &err) != IC_OK) {
                fprintf(stderr, "irrcache %s: %s\n", cmd, err.message);
                ok = 0;
            }
        }
    }
    cJSON_free(text);
    return ok;
}

cJSON *ic_cli_json_u64(uint64_t v)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%llu", (unsigned long long)v);
    return cJSON_CreateRaw(buf);
}
