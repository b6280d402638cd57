/* SPDX-License-Identifier: Apache-2.0 */
/* A main() for a fuzz target without libFuzzer: runs LLVMFuzzerTestOneInput
 * once on every file named, or on every file in each directory named, so
 * plain host builds (and the ASan build) replay the committed corpus and
 * the regression inputs as a CTest test. A violated invariant aborts. */
#define _POSIX_C_SOURCE 200809L /* opendir, stat */

#include <dirent.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Longest input replayed; tools/run-fuzz caps fuzzing at 4096 bytes. */
#define REPLAY_MAX 65536u

static unsigned s_runs;

static int prv_run_file(const char *path)
{
    static uint8_t buf[REPLAY_MAX];
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "replay: cannot open %s\n", path);
        return 1;
    }
    const size_t n = fread(buf, 1, sizeof buf, f);
    const int too_long = !feof(f);
    fclose(f);
    if (too_long) {
        fprintf(stderr, "replay: %s is longer than %u bytes\n", path, REPLAY_MAX);
        return 1;
    }
    /* A fresh copy per run, so reading past the input is caught by ASan. */
    uint8_t copy[REPLAY_MAX];
    memcpy(copy, buf, n);
    (void)LLVMFuzzerTestOneInput(copy, n);
    s_runs++;
    return 0;
}

static int prv_run_path(const char *path)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        fprintf(stderr, "replay: no such file or directory: %s\n", path);
        return 1;
    }
    if (!S_ISDIR(st.st_mode)) {
        return prv_run_file(path);
    }
    DIR *d = opendir(path);
    if (!d) {
        fprintf(stderr, "replay: cannot read %s\n", path);
        return 1;
    }
    int rc = 0;
    char sub[4096];
    for (const struct dirent *e = readdir(d); e; e = readdir(d)) {
        if (e->d_name[0] == '.') {
            continue;
        }
        snprintf(sub, sizeof sub, "%s/%s", path, e->d_name);
        if (stat(sub, &st) == 0 && S_ISREG(st.st_mode)) {
            rc |= prv_run_file(sub);
        }
    }
    closedir(d);
    return rc;
}

int main(int argc, char **argv)
{
    int rc = 0;
    for (int i = 1; i < argc; i++) {
        rc |= prv_run_path(argv[i]);
    }
    printf("replayed %u inputs\n", s_runs);
    return (rc != 0 || s_runs == 0u) ? 1 : 0;
}
