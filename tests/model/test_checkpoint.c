/*
 * Checkpoints: bit-exact round trips, truncated and corrupted files, and
 * the atomic replacement of an existing checkpoint.
 */
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "../harness.h"
#include "ckpt_fixture.h"

/* ---- round trips -------------------------------------------------------- */

static void round_trip(bool full)
{
    char path[128];
    path_in(path, sizeof path, full ? "full.ckpt" : "small.ckpt");
    nerf_model *m = trained_model(full);
    CHECK_OK(nerf_model_save(m, path));
    nerf_hooks h = counting_hooks();
    last_log[0] = '\0';
    live_blocks = 0;
    nerf_model *back = NULL;
    CHECK_OK(nerf_model_load(&back, path, &h));
    CHECK(strstr(last_log, "loaded checkpoint") != NULL);
    if (m && back) {
        check_same_model(m, back);
        CHECK_EQ_INT(back->step, 3);
        /* The loaded model trains on exactly as the original would. */
        nerf__model_zero_grad(m);
        nerf__model_zero_grad(back);
        for (size_t i = 0; i < m->n_params; i++) {
            m->grads[i] = back->grads[i] = (float)cos(0.1 * (double)i);
        }
        nerf__model_adam_step(m);
        nerf__model_adam_step(back);
        check_same_model(m, back);
    }
    nerf_model_destroy(back);
    CHECK_EQ_INT(live_blocks, 0);
    nerf_model_destroy(m);
    CHECK_EQ_INT(count_temp_files(tmpdir), 0);
}

TEST(round_trip_tiny_preset)
{
    round_trip(true);
}

TEST(round_trip_without_fine_or_viewdirs)
{
    round_trip(false);
}

/* Weights and moments go into the zlib stream as they are (compressing
 * noisy floats saved a tenth of their bytes at most, and made a
 * fast-preset save take 6 s): the packed stream holds at least their
 * bytes, and still inflates to the whole model (round_trip). */
TEST(weights_and_moments_are_copied)
{
    char path[128];
    path_in(path, sizeof path, "copied.ckpt");
    nerf_model *m = trained_model(true);
    CHECK_OK(nerf_model_save(m, path));
    size_t size = 0;
    unsigned char *b = fx_slurp(path, &size);
    if (m && b) {
        CHECK(size - HEADER >= 3 * 4 * m->n_params);
    }
    free(b);
    nerf_model_destroy(m);
}

/* Hash-grid models keep their space: the section is required, so a
 * reader that does not know it refuses the file rather than laying the
 * grids over the wrong space. */
TEST(round_trip_keeps_the_space)
{
    const uint32_t spaces[2] = {NERF_SPACE_NDC, NERF_SPACE_UNBOUNDED};
    for (int i = 0; i < 2; i++) {
        nerf_model_options o;
        NERF_MODEL_OPTIONS_INIT(&o);
        CHECK_OK(nerf_model_options_preset(&o, NERF_PRESET_FAST));
        o.hash_log2_size = 12;
        o.hash_levels = 4;
        o.space = spaces[i];
        o.bound = 1.25f;
        nerf_model *m = NULL, *back = NULL;
        CHECK_OK(nerf_model_create(&m, &o));
        char path[128];
        path_in(path, sizeof path, "space.ckpt");
        CHECK_OK(nerf_model_save(m, path));
        CHECK_OK(nerf_model_load(&back, path, NULL));
        if (m && back) {
            check_same_model(m, back);
            nerf_model_options got;
            NERF_MODEL_OPTIONS_INIT(&got);
            CHECK_OK(nerf_model_get_options(back, &got));
            CHECK_EQ_INT(got.space, spaces[i]);
            CHECK(got.bound == 1.25f);
        }
        nerf_model_destroy(back);
        nerf_model_destroy(m);
    }
    /* A frequency model has no grid to place. */
    nerf_model_options o;
    NERF_MODEL_OPTIONS_INIT(&o);
    o.space = NERF_SPACE_NDC;
    nerf_model *m = NULL;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
    CHECK(strstr(nerf_last_error(), "space") != NULL);
    o.space = 3;
    CHECK_EQ_INT(nerf_model_create(&m, &o), NERF_EINVAL);
}

TEST(arguments)
{
    nerf_model *m = trained_model(false);
    nerf_model *out = NULL;
    CHECK_EQ_INT(nerf_model_save(NULL, "x"), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_save(m, NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_load(NULL, "x", NULL), NERF_EINVAL);
    CHECK_EQ_INT(nerf_model_load(&out, NULL, NULL), NERF_EINVAL);
    CHECK(out == NULL);
    nerf_model_destroy(m);
}

/* ---- damaged files ------------------------------------------------------ */
TEST(truncated_files)
{
    size_t size = 0;
    unsigned char *good = good_file(&size);
    char path[128];
    path_in(path, sizeof path, "cut.ckpt");
    size_t lengths[128];
    int n = 0;
    for (size_t len = 0; len <= 64; len++) {
        lengths[n++] = len;
    }
    for (int k = 1; k <= 40; k++) {
        lengths[n++] = 64 + (size - 65) * (size_t)k / 40;
    }
    lengths[n++] = size - 1;
    for (int i = 0; i < n; i++) {
        spit(path, good, lengths[i]);
        char what[64];
        snprintf(what, sizeof what, "cut to %zu of %zu bytes", lengths[i],
                 size);
        expect_load_fails(path, NERF_EFORMAT, what);
    }
    free(good);
}

TEST(bit_flips)
{
    size_t size = 0;
    unsigned char *good = good_file(&size);
    char path[128];
    path_in(path, sizeof path, "flip.ckpt");
    /* Every bit of the header, then bytes spread over the payload. */
    size_t positions[HEADER * 8 + 300][2];
    int n = 0;
    for (size_t bit = 0; bit < HEADER * 8; bit++) {
        positions[n][0] = bit / 8;
        positions[n++][1] = bit % 8;
    }
    for (size_t k = 0; k < 300; k++) {
        positions[n][0] = HEADER + (size - HEADER - 1) * k / 299;
        positions[n++][1] = k % 8;
    }
    for (int i = 0; i < n; i++) {
        size_t at = positions[i][0];
        good[at] ^= (unsigned char)(1u << positions[i][1]);
        spit(path, good, size);
        good[at] ^= (unsigned char)(1u << positions[i][1]);
        char what[64];
        snprintf(what, sizeof what, "bit %zu of byte %zu flipped",
                 positions[i][1], at);
        /* A flip within the 8-byte magic leaves no checkpoint to read. */
        expect_load_fails(path, at < 8 ? NERF_EUNRECOGNISED : NERF_EFORMAT,
                          what);
    }
    /* An extra byte at the end is damage too. */
    unsigned char *longer = malloc(size + 1);
    memcpy(longer, good, size);
    longer[size] = 0;
    spit(path, longer, size + 1);
    expect_load_fails(path, NERF_EFORMAT, "trailing byte");
    free(longer);
    free(good);
}

TEST(wrong_magic_and_future_version)
{
    size_t size = 0;
    unsigned char *b = good_file(&size);
    char path[128];
    path_in(path, sizeof path, "other.ckpt");
    memcpy(b, "NERFCKPX", 8);
    spit(path, b, size);
    expect_load_fails(path, NERF_EUNRECOGNISED, "wrong magic");
    CHECK(strstr(nerf_last_error(), "not a libnerf checkpoint") != NULL);
    spit(path, "PK\3\4 something else entirely", 28);
    expect_load_fails(path, NERF_EUNRECOGNISED, "a zip file");
    CHECK(strstr(nerf_last_error(), "not a libnerf checkpoint") != NULL);

    memcpy(b, "NERFCKPT", 8);
    put32(b + 8, 3);
    fix_header_crc(b);
    spit(path, b, size);
    expect_load_fails(path, NERF_EVERSION, "format version 3");
    CHECK(strstr(nerf_last_error(), "version 3") != NULL);
    CHECK(strstr(nerf_last_error(), "version 2") != NULL);
    /* A future header may be longer; its CRC still sits at its end. */
    unsigned char *big = calloc(1, size + 16);
    memcpy(big, b, 44);
    put32(big + 12, HEADER + 16);
    put32(big + HEADER + 12, (uint32_t)crc32(0L, big, HEADER + 12));
    spit(path, big, size + 16);
    expect_load_fails(path, NERF_EVERSION, "version 3, longer header");
    free(big);
    /* Unknown header flags mean features this reader lacks. */
    put32(b + 8, 1);
    put32(b + 40, 1);
    fix_header_crc(b);
    spit(path, b, size);
    expect_load_fails(path, NERF_EVERSION, "header flags");
    free(b);
}

TEST(missing_and_unreadable_paths)
{
    char path[128];
    path_in(path, sizeof path, "does-not-exist.ckpt");
    /* Named for what they are, not as input/output failures. */
    expect_load_fails(path, NERF_ENOENT, "missing file");
    CHECK(strstr(nerf_last_error(), "cannot open") != NULL);
    CHECK(strcmp(nerf_status_string(NERF_ENOENT), "no such file or folder")
          == 0);
    expect_load_fails(tmpdir, NERF_EUNRECOGNISED, "a directory");
    CHECK(strstr(nerf_last_error(), "a folder, not a file") != NULL);
    /* Refused without being opened for reading: a FIFO without a writer
     * would block the load for ever. */
    path_in(path, sizeof path, "fifo.ckpt");
    CHECK(mkfifo(path, 0666) == 0);
    expect_load_fails(path, NERF_EUNRECOGNISED, "a FIFO");
    CHECK(strstr(nerf_last_error(), "a FIFO (named pipe), not a regular "
                 "file") != NULL);
    unlink(path);
    expect_load_fails("/dev/null", NERF_EUNRECOGNISED, "a device");
    CHECK(strstr(nerf_last_error(), "a character device") != NULL);
}

/* ---- atomic replacement ------------------------------------------------- */

TEST(save_into_missing_directory)
{
    char path[160];
    path_in(path, sizeof path, "no-such-dir/model.ckpt");
    nerf_model *m = trained_model(false);
    CHECK_EQ_INT(nerf_model_save(m, path), NERF_EIO);
    CHECK(strstr(nerf_last_error(), path) == nerf_last_error());
    CHECK_EQ_INT(count_temp_files(tmpdir), 0);
    nerf_model_destroy(m);
}

TEST(failed_save_keeps_the_old_checkpoint)
{
    char path[128];
    path_in(path, sizeof path, "keep.ckpt");
    nerf_model *old = trained_model(false), *other = trained_model(true);
    CHECK_OK(nerf_model_save(old, path));
    size_t size = 0;
    unsigned char *before = fx_slurp(path, &size);

    /* A full disk, simulated with a file size limit (this works as root,
     * where a read-only directory would not stop the write). */
    struct rlimit saved, small;
    getrlimit(RLIMIT_FSIZE, &saved);
    small = saved;
    small.rlim_cur = 4096;
    void (*prev)(int) = signal(SIGXFSZ, SIG_IGN);
    CHECK(setrlimit(RLIMIT_FSIZE, &small) == 0);
    int rc = nerf_model_save(other, path);
    setrlimit(RLIMIT_FSIZE, &saved);
    signal(SIGXFSZ, prev);
    CHECK_EQ_INT(rc, NERF_EIO);
    CHECK(strstr(nerf_last_error(), path) == nerf_last_error());

    size_t after_size = 0;
    unsigned char *after = fx_slurp(path, &after_size);
    CHECK(after && after_size == size && memcmp(before, after, size) == 0);
    CHECK_EQ_INT(count_temp_files(tmpdir), 0);
    free(after);

    /* The rename fails when the target is a directory. */
    char dir[128], inner[160];
    path_in(dir, sizeof dir, "a-directory");
    mkdir(dir, 0755);
    snprintf(inner, sizeof inner, "%s/file", dir);
    spit(inner, "x", 1);
    CHECK_EQ_INT(nerf_model_save(other, dir), NERF_EIO);
    CHECK(strstr(nerf_last_error(), dir) == nerf_last_error());
    CHECK_EQ_INT(count_temp_files(tmpdir), 0);

    if (geteuid() != 0) {
        chmod(tmpdir, 0555);
        CHECK_EQ_INT(nerf_model_save(other, path), NERF_EIO);
        chmod(tmpdir, 0755);
        after = fx_slurp(path, &after_size);
        CHECK(after && after_size == size && memcmp(before, after, size) == 0);
        free(after);
    }

    /* A successful save replaces the old file completely. */
    CHECK_OK(nerf_model_save(other, path));
    nerf_model *back = NULL;
    CHECK_OK(nerf_model_load(&back, path, NULL));
    if (back && other) {
        check_same_model(back, other);
    }
    CHECK_EQ_INT(count_temp_files(tmpdir), 0);
    nerf_model_destroy(back);
    free(before);
    nerf_model_destroy(old);
    nerf_model_destroy(other);
}

static bool exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/*
 * A save killed mid-write (kill -9) leaves path.tmp.<pid>.<n>: the next
 * save of path removes those of dead pids, and nothing else.
 */
TEST(stale_temp_files_are_removed)
{
    char dir[160], path[200], name[260];
    path_in(dir, sizeof dir, "stale");
    mkdir(dir, 0755);
    snprintf(path, sizeof path, "%s/model.ckpt", dir);
    /* A pid that surely belongs to no process: a child that has exited
     * and been reaped. */
    pid_t dead = fork();
    if (dead == 0) {
        _exit(0);
    }
    CHECK(dead > 0);
    waitpid(dead, NULL, 0);
    static const char *const gone[] = {"model.ckpt.tmp.%ld.0",
                                       "model.ckpt.tmp.%ld.17"};
    static const char *const kept[] = {
        "model.ckpt.tmp.%ld.x",   /* not the library's pattern */
        "model.ckpt.tmp.%ld",     /* nor this */
        "other.ckpt.tmp.%ld.0",   /* another file's */
        "xmodel.ckpt.tmp.%ld.0",  /* another file's */
    };
    for (size_t i = 0; i < 2; i++) {
        char base[64];
        snprintf(base, sizeof base, gone[i], (long)dead);
        snprintf(name, sizeof name, "%s/%s", dir, base);
        spit(name, "x", 1);
    }
    for (size_t i = 0; i < sizeof kept / sizeof kept[0]; i++) {
        char base[64];
        snprintf(base, sizeof base, kept[i], (long)dead);
        snprintf(name, sizeof name, "%s/%s", dir, base);
        spit(name, "x", 1);
    }
    /* A live writer's (our own pid, and pid 1) stays. */
    char live[2][260];
    snprintf(live[0], sizeof live[0], "%s.tmp.%ld.5", path, (long)getpid());
    snprintf(live[1], sizeof live[1], "%s.tmp.1.0", path);
    spit(live[0], "x", 1);
    spit(live[1], "x", 1);

    nerf_model *m = trained_model(false);
    CHECK_OK(nerf_model_save(m, path));
    for (size_t i = 0; i < 2; i++) {
        char base[64];
        snprintf(base, sizeof base, gone[i], (long)dead);
        snprintf(name, sizeof name, "%s/%s", dir, base);
        if (exists(name)) {
            FAILF("%s was not removed", name);
        }
    }
    for (size_t i = 0; i < sizeof kept / sizeof kept[0]; i++) {
        char base[64];
        snprintf(base, sizeof base, kept[i], (long)dead);
        snprintf(name, sizeof name, "%s/%s", dir, base);
        if (!exists(name)) {
            FAILF("%s was removed", name);
        }
        unlink(name);
    }
    CHECK(exists(live[0]) && exists(live[1]));
    unlink(live[0]);
    unlink(live[1]);
    unlink(path);
    rmdir(dir);
    nerf_model_destroy(m);
}

int main(void)
{
    make_tmpdir();
    RUN(round_trip_tiny_preset);
    RUN(round_trip_without_fine_or_viewdirs);
    RUN(round_trip_keeps_the_space);
    RUN(weights_and_moments_are_copied);
    RUN(arguments);
    RUN(truncated_files);
    RUN(bit_flips);
    RUN(wrong_magic_and_future_version);
    RUN(missing_and_unreadable_paths);
    RUN(save_into_missing_directory);
    RUN(failed_save_keeps_the_old_checkpoint);
    RUN(stale_temp_files_are_removed);
    remove_tree(tmpdir);
    HARNESS_EXIT();
}
