/* json_out.h — JSON the command writes (--stats, --records-json, diff --json), through cJSON's writer. */
#ifndef IC_CLI_JSON_OUT_H
#define IC_CLI_JSON_OUT_H

#include <cjson/cJSON.h>
#include <stdint.h>

/* Writes root (pretty-printed, or on one line) to path through a temporary file renamed on success, or to stdout when
 * path is NULL; frees root. On failure prints "irrcache CMD: message" and returns 0. */
int ic_cli_write_json(const char *cmd, const char *path, cJSON *root, int pretty);
/* s with every byte that is not part of well-formed UTF-8 replaced by U+FFFD (allocated with cJSON_malloc, freed
 * with cJSON_free), or NULL when s is already well-formed (or out of memory: *oom set). */
char *ic_cli_utf8_repaired(const char *s, int *oom);
/* Repairs every string value and key of the tree from item on (its siblings and children) as
 * ic_cli_utf8_repaired does, in place (the repaired text replaces the old, owned or not, and is freed by
 * cJSON_Delete); 0 if out of memory. ic_cli_write_json does it before writing. */
int ic_cli_json_utf8(cJSON *item);
/* An exact unsigned integer (cJSON's numbers are doubles: counts above 2^53 would round). */
cJSON *ic_cli_json_u64(uint64_t v);

#endif
