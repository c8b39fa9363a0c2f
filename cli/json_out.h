/* json_out.h — JSON the command writes (--stats, --records-json, diff --json), through cJSON's writer. */
#ifndef IC_CLI_JSON_OUT_H
#define IC_CLI_JSON_OUT_H

#include <cjson/cJSON.h>
#include <stdint.h>

/* Writes root (pretty-printed, or on one line) to path through a temporary file renamed on success, or to stdout when
 * path is NULL; frees root. On failure prints "irrcache CMD: message" and returns 0. */
int ic_cli_write_json(const char *cmd, const char *path, cJSON *root, int pretty);
/* An exact unsigned integer (cJSON's numbers are doubles: counts above 2^53 would round). */
cJSON *ic_cli_json_u64(uint64_t v);

#endif
