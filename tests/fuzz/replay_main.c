/*
 * replay_main.c — a main for a harness outside libFuzzer: feeds every file named on the command line, and
 * every regular file of every folder named (in name order, dot-files skipped), to LLVMFuzzerTestOneInput.
 * A folder that does not exist is skipped (tests/fuzz/regress/<target>/ may be absent). Prints one line:
 * "<argv[0]>: N inputs replayed"; no input at all is a failure. A crash, a sanitizer report or a leak
 * (in the ASan build) fails the run, as under libFuzzer.
 */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int replay_file(const char *path)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        fprintf(stderr, "replay: cannot open %s (%s)\n", path, strerror(errno));
        return -1;
    }
    size_t cap = 1 << 16, size = 0;
    uint8_t *data = malloc(cap);
    size_t n;
    while (data && (n = fread(data + size, 1, cap - size, fp)) > 0) {
        size += n;
        if (size == cap) {
            uint8_t *grown = realloc(data, cap * 2);
            if (!grown) {
                free(data);
                data = NULL;
                break;
            }
            data = grown;
            cap *= 2;
        }
    }
    int bad = ferror(fp) || !data;
    fclose(fp);
    if (bad) {
        free(data);
        fprintf(stderr, "replay: cannot read %s\n", path);
        return -1;
    }
    /* An exact-size copy, so that ASan catches a read one past the input's end. */
    uint8_t *exact = malloc(size ? size : 1);
    if (!exact) {
        free(data);
        return -1;
    }
    memcpy(exact, data, size);
    free(data);
    if (getenv("IC_REPLAY_VERBOSE"))
        fprintf(stderr, "replay: %s (%zu bytes)\n", path, size);
    LLVMFuzzerTestOneInput(exact, size);
    free(exact);
    return 0;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

int main(int argc, char **argv)
{
    long replayed = 0;
    int failed = 0;
    for (int a = 1; a < argc; ++a) {
        struct stat st;
        if (stat(argv[a], &st) != 0)
            continue; /* no such folder: nothing to replay */
        if (!S_ISDIR(st.st_mode)) {
            failed |= replay_file(argv[a]) != 0;
            replayed++;
            continue;
        }
        DIR *d = opendir(argv[a]);
        if (!d) {
            fprintf(stderr, "replay: cannot open folder %s\n", argv[a]);
            failed = 1;
            continue;
        }
        char **names = NULL;
        size_t count = 0, cap = 0;
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (e->d_name[0] == '.')
                continue;
            if (count == cap) {
                cap = cap ? cap * 2 : 64;
                char **grown = realloc(names, cap * sizeof *names);
                if (!grown)
                    abort();
                names = grown;
            }
            names[count] = malloc(strlen(argv[a]) + strlen(e->d_name) + 2);
            if (!names[count])
                abort();
            sprintf(names[count], "%s/%s", argv[a], e->d_name);
            count++;
        }
        closedir(d);
        if (count)
            qsort(names, count, sizeof *names, by_name);
        for (size_t k = 0; k < count; ++k) {
            if (stat(names[k], &st) == 0 && S_ISREG(st.st_mode)) {
                failed |= replay_file(names[k]) != 0;
                replayed++;
            }
            free(names[k]);
        }
        free(names);
    }
    printf("%s: %ld inputs replayed\n", argv[0], replayed);
    if (replayed == 0)
        fprintf(stderr, "replay: no input found (a target's seed corpus must not be empty)\n");
    return failed || replayed == 0 ? 1 : 0;
}
