/* json_out.c — writing JSON files atomically (json_out.h). */
#include "json_out.h"

#include "cli.h"

#include "core/atomic_file.h"
#include "core/text.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

char *ic_cli_utf8_repaired(const char *s, int *oom)
{
    const unsigned char *p = (const unsigned char *)s;
    size_t n;
    while (*p && (n = ic_utf8_sequence(p, SIZE_MAX)) > 0)
        p += n;
    if (!*p)
        return NULL;
    char *out = cJSON_malloc(3 * strlen(s) + 1), *q = out;
    if (!out) {
        *oom = 1;
        return NULL;
    }
    for (p = (const unsigned char *)s; *p;) {
        n = ic_utf8_sequence(p, SIZE_MAX);
        if (n) {
            memcpy(q, p, n);
            q += n;
            p += n;
        } else {
            memcpy(q, "\xEF\xBF\xBD", 3);
            q += 3;
            ++p;
        }
    }
    *q = '\0';
    return out;
}

/* cJSON escapes quotes, backslashes and control characters but copies other bytes as they are, and
 * JSON text must be UTF-8: a path in another encoding (a Latin-1 file name) would make the whole file
 * unreadable to a strict parser. */
int ic_cli_json_utf8(cJSON *item)
{
    for (; item; item = item->next) {
        int oom = 0;
        if (cJSON_IsString(item) && item->valuestring) {
            char *fixed = ic_cli_utf8_repaired(item->valuestring, &oom);
            if (fixed) {
                if (!(item->type & cJSON_IsReference))
                    cJSON_free(item->valuestring);
                item->type &= ~cJSON_IsReference; /* the repaired copy is the item's own */
                item->valuestring = fixed;
            }
        }
        if (!oom && item->string) {
            char *fixed = ic_cli_utf8_repaired(item->string, &oom);
            if (fixed) {
                if (!(item->type & cJSON_StringIsConst))
                    cJSON_free(item->string);
                item->type &= ~cJSON_StringIsConst;
                item->string = fixed;
            }
        }
        if (oom || !ic_cli_json_utf8(item->child))
            return 0;
    }
    return 1;
}

int ic_cli_write_json(const char *cmd, const char *path, cJSON *root, int pretty)
{
    char *text = !root || !ic_cli_json_utf8(root) ? NULL : pretty ? cJSON_Print(root) : cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    if (!text) {
        ic_cli_eprintf("irrcache %s: out of memory writing %s\n", cmd, path ? path : "JSON");
        return 0;
    }
    int ok = 1;
    if (!path) {
        char who[64];
        snprintf(who, sizeof who, "irrcache %s", cmd);
        puts(text);
        ok = !ic_cli_flush_stdout(who);
    } else {
        ic_atomic_file f;
        ic_error err;
        if (ic_atomic_file_open(&f, path, &err) != IC_OK) {
            ic_cli_eprintf("irrcache %s: %s\n", cmd, err.message);
            ok = 0;
        } else {
            fputs(text, f.fp);
            fputc('\n', f.fp);
            if (ic_atomic_file_commit(&f, &err) != IC_OK) {
                ic_cli_eprintf("irrcache %s: %s\n", cmd, err.message);
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
