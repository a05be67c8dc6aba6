/* CLI helpers: error lines, strict option parsing, whole-file reads,
 * atomic output files, the monotonic clock and DEM loading. */
/* realpath() is XSI */
#ifndef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700
#endif
#include "cli.h"
#include "bigalloc.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <locale.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static const char *error_context;

void cli_error_context(const char *context) { error_context = context; }

/* A thread's captured error line (cli_error_capture): the key made once. */
static pthread_key_t capture_key;
static pthread_once_t capture_once = PTHREAD_ONCE_INIT;
static int capture_ok;
static void capture_init(void) { capture_ok = pthread_key_create(&capture_key, NULL) == 0; }

int cli_error_capture(char *buf)
{
    pthread_once(&capture_once, capture_init);
    if (!capture_ok || pthread_setspecific(capture_key, buf) != 0) return 1;
    if (buf) buf[0] = 0;
    return 0;
}

void cli_error(const char *fmt, ...)
{
    va_list ap;
    char *cap = NULL;
    if (capture_ok) cap = pthread_getspecific(capture_key);
    if (cap) { /* the first line only: it is the cause */
        if (!cap[0]) {
            int n = snprintf(cap, CLI_ERROR_CAP, "roadsplat: %s%s", error_context ? error_context : "",
                             error_context ? ": " : "");
            va_start(ap, fmt);
            if (n >= 0 && n < CLI_ERROR_CAP) vsnprintf(cap + n, CLI_ERROR_CAP - (size_t)n, fmt, ap);
            va_end(ap);
        }
        return;
    }
    fputs("roadsplat: ", stderr);
    if (error_context) {
        fputs(error_context, stderr);
        fputs(": ", stderr);
    }
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

double cli_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1000.0 + (double)ts.tv_nsec / 1e6;
}

/* ---- numbers -------------------------------------------------------------- */

/* Parse [s, s+n) as a decimal number with the same rules as the library's
 * files: sign, digits, '.', exponent; no comma, hex, inf or nan. strtod
 * does the conversion, but only after the characters are checked, and on a
 * copy whose '.' is replaced by the current locale's decimal point, so a
 * host locale can neither break nor widen what is accepted. */
static int strict_double(const char *s, size_t n, double *out) /* 1 ok, 0 bad, -1 out of range */
{
    char buf[128];
    int digits = 0;
    if (n == 0 || n >= sizeof buf - 8) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (c >= '0' && c <= '9') digits = 1;
        else if (c != '+' && c != '-' && c != '.' && c != 'e' && c != 'E') return 0;
    }
    if (!digits) return 0;
    const char *dp = localeconv()->decimal_point;
    size_t dpl = dp && dp[0] ? strlen(dp) : 1, o = 0;
    if (dpl > 4) return 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '.' && dp && dp[0]) { memcpy(buf + o, dp, dpl); o += dpl; }
        else buf[o++] = s[i];
    }
    buf[o] = '\0';
    char *end;
    errno = 0;
    double v = strtod(buf, &end);
    if (end != buf + o) return 0;
    if (!isfinite(v) || (errno == ERANGE && fabs(v) > 1.0)) return -1;
    *out = v;
    return 1;
}

int cli_parse_double(const char *option, const char *s, double *out)
{
    int k = s ? strict_double(s, strlen(s), out) : 0;
    if (k < 0) {
        cli_error("%s: '%s' is out of range", option, s);
        return 1;
    }
    if (k == 0) {
        cli_error("%s: '%s' is not a number%s", option, s ? s : "",
                  s && strchr(s, ',') ? " (use '.' as the decimal point)" : "");
        return 1;
    }
    return 0;
}

static int strict_u32(const char *s, size_t n, uint32_t *out)
{
    uint64_t v = 0;
    if (n == 0) return 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return 0;
        v = v * 10 + (uint64_t)(s[i] - '0');
        if (v > UINT32_MAX) return 0;
    }
    *out = (uint32_t)v;
    return 1;
}

int cli_parse_u32(const char *option, const char *s, uint32_t *out)
{
    if (!s || !strict_u32(s, strlen(s), out)) {
        cli_error("%s: '%s' is not a whole number in 0..4294967295", option, s ? s : "");
        return 1;
    }
    return 0;
}

int cli_parse_vec(const char *option, const char *s, double *out, int n)
{
    const char *p = s;
    int i = 0;
    if (s && n >= 1 && n <= 4) {
        for (; i < n; i++) {
            const char *c = strchr(p, ',');
            size_t len = c ? (size_t)(c - p) : strlen(p);
            if (strict_double(p, len, &out[i]) != 1) break;
            if (i == n - 1) { if (c) break; }
            else if (!c) break;
            p = c ? c + 1 : p + len;
        }
    }
    if (i != n) {
        cli_error("%s: '%s' is not %s (numbers with '.' as the decimal point, separated by ',')", option,
                  s ? s : "", n == 3 ? "X,Y,Z" : "X,Y");
        return 1;
    }
    return 0;
}

int cli_parse_size(const char *option, const char *s, uint32_t *w, uint32_t *h)
{
    const char *x = s ? strpbrk(s, "xX") : NULL;
    if (!x || !strict_u32(s, (size_t)(x - s), w) || !strict_u32(x + 1, strlen(x + 1), h) || !*w || !*h) {
        cli_error("%s: '%s' is not a size WxH (positive whole numbers)", option, s ? s : "");
        return 1;
    }
    return 0;
}

/* ---- files ---------------------------------------------------------------- */

static char *dup_str(const char *s);

int cli_read_file(const char *path, size_t limit, char **data, size_t *size)
{
    return cli_read_input(path, NULL, limit, data, size);
}

int cli_read_input(const char *path, const char *role, size_t limit, char **data, size_t *size)
{
    *data = NULL;
    *size = 0;
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) { cli_error("%s: %s", path, strerror(errno)); return 1; }
    FILE *f = fdopen(fd, "rb");
    if (!f) { cli_error("%s: %s", path, strerror(errno)); close(fd); return 1; }
    struct stat st;
    memset(&st, 0, sizeof st);
    if (fstat(fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
        fclose(f);
        cli_error("%s: is a directory", path);
        return 1;
    }
    if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode) && !S_ISSOCK(st.st_mode)) { /* /dev/zero never ends */
        fclose(f);
        cli_error("%s: is a device; inputs must be regular files or pipes", path);
        return 1;
    }
    if (limit && S_ISREG(st.st_mode) && (uint64_t)st.st_size > (uint64_t)limit) { /* before allocating */
        fclose(f);
        cli_error("%s: file is larger than the %zu-byte limit", path, limit);
        return 1;
    }
    size_t cap = 1 << 16, n = 0;
    if (S_ISREG(st.st_mode) && st.st_size > 0 && (uint64_t)st.st_size < SIZE_MAX - 1) cap = (size_t)st.st_size + 1;
    if (limit && cap > limit + 1) cap = limit + 1;
    char *buf = malloc(cap);
    if (!buf) { fclose(f); cli_error("%s: out of memory", path); return 1; }
    for (;;) {
        if (n + 1 >= cap) { /* keep room for the terminating NUL */
            if (limit && n > limit) break;
            size_t nc = cap > SIZE_MAX / 2 ? SIZE_MAX : cap * 2;
            if (limit && nc > limit + 2) nc = limit + 2;
            char *nb = nc > cap ? realloc(buf, nc) : NULL;
            if (!nb) { free(buf); fclose(f); cli_error("%s: out of memory", path); return 1; }
            buf = nb;
            cap = nc;
        }
        size_t got = fread(buf + n, 1, cap - 1 - n, f);
        n += got;
        if (got == 0) break;
    }
    int err = ferror(f);
    int saved = errno;
    if (err) { fclose(f); free(buf); cli_error("%s: read error: %s", path, strerror(saved)); return 1; }
    if (limit && n > limit) {
        fclose(f);
        free(buf);
        cli_error("%s: file is larger than the %zu-byte limit", path, limit);
        return 1;
    }
    buf[n] = '\0';
    /* registered from the descriptor read, with the bytes read (a pipe) */
    int bad = role && cli_inputs_add(path, role, fileno(f), buf, n);
    fclose(f);
    if (bad) { free(buf); return 1; }
    *data = buf;
    *size = n;
    return 0;
}

/* ---- the run's inputs ---------------------------------------------------------- */

/* Every file a run reads (docs/ROBUSTNESS.md, "trust model"): for the
 * output-collision check at commit and for hashing what was loaded
 * (tiles' manifest). A regular file keeps a descriptor of the inode that
 * was read; a pipe's bytes are kept in an unlinked temporary file. */
typedef struct input_entry {
    char *path, *role;
    dev_t dev;
    ino_t ino;
    int replaceable; /* a file or folder (not a pipe): an output could replace it */
    int fd;          /* the bytes loaded (from offset 0); -1: not kept (a folder) */
} input_entry;

static input_entry *inputs;
static size_t ninputs, cap_inputs;
static int keep_pipe_bytes; /* cli_inputs_keep_pipes */

void cli_inputs_keep_pipes(int on) { keep_pipe_bytes = on != 0; }

static int input_push(const char *path, const char *role, const struct stat *st, int fd)
{
    if (ninputs == cap_inputs) {
        size_t nc = cap_inputs ? 2 * cap_inputs : 16;
        input_entry *p = realloc(inputs, nc * sizeof *p);
        if (!p) return 1;
        inputs = p;
        cap_inputs = nc;
    }
    input_entry *e = &inputs[ninputs];
    e->path = dup_str(path);
    e->role = dup_str(role);
    if (!e->path || !e->role) {
        free(e->path);
        free(e->role);
        return 1;
    }
    e->dev = st ? st->st_dev : 0;
    e->ino = st ? st->st_ino : 0;
    e->replaceable = st && (S_ISREG(st->st_mode) || S_ISDIR(st->st_mode));
    e->fd = fd;
    ninputs++;
    return 0;
}

int cli_inputs_add(const char *path, const char *role, int fd, const void *data, size_t size)
{
    struct stat st;
    if (fstat(fd, &st) != 0) { cli_error("%s: %s", path, strerror(errno)); return 1; }
    int keep = -1;
    if (S_ISDIR(st.st_mode)) { /* a GIS source folder: checked by inode, not hashed */
        if (input_push(path, role, &st, -1)) {
            cli_error("out of memory");
            return 1;
        }
        return 0;
    }
    if (S_ISREG(st.st_mode)) {
        /* a file read again in that role (a loader called in a loop) is one entry */
        for (size_t i = 0; i < ninputs; i++)
            if (inputs[i].dev == st.st_dev && inputs[i].ino == st.st_ino && !strcmp(inputs[i].role, role)) return 0;
        keep = fcntl(fd, F_DUPFD_CLOEXEC, 3);
    } else if (data && !keep_pipe_bytes) { /* a pipe nobody will hash: nothing to keep */
        if (input_push(path, role, &st, -1)) {
            cli_error("out of memory");
            return 1;
        }
        return 0;
    } else if (data) { /* a pipe: its bytes, as read */
        FILE *t = tmpfile();
        if (t && fwrite(data, 1, size, t) == size && fflush(t) == 0) keep = fcntl(fileno(t), F_DUPFD_CLOEXEC, 3);
        if (t) fclose(t);
    } else {
        keep = fcntl(fd, F_DUPFD_CLOEXEC, 3); /* a copy already (cli_load_*) */
    }
    if (keep < 0 || input_push(path, role, &st, keep)) {
        if (keep >= 0) close(keep);
        cli_error("%s: cannot keep track of the input: %s", path, strerror(errno ? errno : ENOMEM));
        return 1;
    }
    return 0;
}

size_t cli_inputs_count(void) { return ninputs; }

int cli_inputs_get(size_t i, const char **path, const char **role)
{
    if (i >= ninputs) return -1;
    if (path) *path = inputs[i].path;
    if (role) *role = inputs[i].role;
    return inputs[i].fd;
}

int cli_inputs_check_output(const char *path, const char *role)
{
    struct stat so;
    if (!path || stat(path, &so) != 0) return 0; /* not there yet: replaces nothing */
    for (size_t i = 0; i < ninputs; i++) {
        const input_entry *e = &inputs[i];
        if (e->replaceable && e->dev == so.st_dev && e->ino == so.st_ino) {
            cli_error("%s: %s is also the %s (%s); refusing to overwrite an input", path, role, e->role, e->path);
            return 1;
        }
    }
    return 0;
}

void cli_inputs_clear(void)
{
    for (size_t i = 0; i < ninputs; i++) {
        if (inputs[i].fd >= 0) close(inputs[i].fd);
        free(inputs[i].path);
        free(inputs[i].role);
    }
    free(inputs);
    inputs = NULL;
    ninputs = cap_inputs = 0;
}

static char *dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

/* ---- temporaries and signals ------------------------------------------------ */

/* Every temporary file the CLI creates is registered here until it is
 * renamed or removed, so that SIGINT, SIGTERM and SIGHUP can remove them
 * all (unlink is async-signal-safe) before exiting with 128 + signal. The
 * paths live in static storage: the handler reads nothing malloc'd. */
#define CLI_MAX_TEMPS 8
/* cli_input_read_all: buffers from this size are faulted in at once */
#define PREFAULT_MIN ((size_t)256 << 10)
#define CLI_TEMP_PATH 4112
static char temp_paths[CLI_MAX_TEMPS][CLI_TEMP_PATH];
static volatile sig_atomic_t temp_used[CLI_MAX_TEMPS];

static void on_signal(int sig)
{
    for (int i = 0; i < CLI_MAX_TEMPS; i++)
        if (temp_used[i]) unlink(temp_paths[i]);
    _exit(128 + sig);
}

static const int handled_signals[3] = { SIGINT, SIGTERM, SIGHUP };

void cli_signals_install(void)
{
    for (int i = 0; i < 3; i++) {
        struct sigaction sa, old;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigfillset(&sa.sa_mask);
        /* a signal ignored on entry (nohup) stays ignored */
        if (sigaction(handled_signals[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN) continue;
        sigaction(handled_signals[i], &sa, NULL);
    }
}

/* Block / unblock the handled signals (around creating and registering a
 * temporary, and around renaming a run's outputs into place). */
static void signals_block(int block, sigset_t *saved)
{
    sigset_t set;
    sigemptyset(&set);
    for (int i = 0; i < 3; i++) sigaddset(&set, handled_signals[i]);
    if (block) sigprocmask(SIG_BLOCK, &set, saved);
    else sigprocmask(SIG_SETMASK, saved, NULL);
}

/* Register a temporary (call with the signals blocked). 0, or 1 when the
 * table is full or the path too long (the caller then removes it). */
static int temp_register(const char *path)
{
    size_t n = strlen(path);
    if (n >= CLI_TEMP_PATH) return 1;
    for (int i = 0; i < CLI_MAX_TEMPS; i++)
        if (!temp_used[i]) {
            memcpy(temp_paths[i], path, n + 1);
            temp_used[i] = 1;
            return 0;
        }
    return 1;
}

void cli_temp_forget(const char *path)
{
    if (!path) return;
    for (int i = 0; i < CLI_MAX_TEMPS; i++)
        if (temp_used[i] && !strcmp(temp_paths[i], path)) temp_used[i] = 0;
}

/* A temporary file "DIR/.rs-XXXXXX" next to `path`: its name has a fixed
 * length, so any OUT name the file system accepts also works for its
 * temporary. Registered for removal on a signal. Returns the descriptor
 * (tmp gets the name) or -1 with errno set. */
int cli_temp_create(const char *path, char **tmp)
{
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path) + 1 : 0;
    *tmp = malloc(dirlen + 16);
    if (!*tmp) { errno = ENOMEM; return -1; }
    memcpy(*tmp, path, dirlen);
    memcpy(*tmp + dirlen, ".rs-XXXXXX", 11);
    sigset_t saved;
    signals_block(1, &saved);
    int fd = mkstemp(*tmp);
    int e = errno;
    if (fd >= 0 && temp_register(*tmp)) {
        close(fd);
        unlink(*tmp);
        fd = -1;
        e = ENAMETOOLONG;
    }
    signals_block(0, &saved);
    if (fd < 0) {
        free(*tmp);
        *tmp = NULL;
        errno = e;
        return -1;
    }
    /* mkstemp makes 0600; give the output the usual 0666 & ~umask. */
    mode_t mask = umask(0);
    umask(mask);
    if (fchmod(fd, 0666 & ~mask) != 0) { /* not fatal */ }
    return fd;
}

/* A temporary of the caller's name `tmp` (unique to the run: tiles'
 * ".NAME.RUNID.part"), made new with O_EXCL | O_NOFOLLOW, so nothing
 * planted under that name (a symbolic link, another run's file) is
 * followed or truncated; 0666 & ~umask; registered for removal on a
 * signal. Returns the descriptor or -1 with errno set. */
int cli_temp_create_named(const char *tmp)
{
    sigset_t saved;
    signals_block(1, &saved);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    int e = errno;
    if (fd >= 0 && temp_register(tmp)) {
        close(fd);
        unlink(tmp);
        fd = -1;
        e = ENAMETOOLONG;
    }
    signals_block(0, &saved);
    if (fd < 0) errno = e;
    return fd;
}

/* Remove a temporary made by cli_temp_create and forget it. */
void cli_temp_remove(const char *tmp)
{
    if (!tmp) return;
    unlink(tmp);
    cli_temp_forget(tmp);
}

static int refuse_non_regular(const char *path)
{
    /* rename() would replace a device, FIFO or folder entry instead of
     * writing to it (as root even /dev/full): only regular files are OUT. */
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        cli_error("%s: %s; the output must be a regular file", path,
                  S_ISDIR(st.st_mode) ? "is a directory" : "exists and is not a regular file");
        return 1;
    }
    return 0;
}

int cli_out_open(cli_out *o, const char *path)
{
    memset(o, 0, sizeof *o);
    if (refuse_non_regular(path)) return 1;
    o->path = dup_str(path);
    if (!o->path) {
        cli_error("%s: out of memory", path);
        return 1;
    }
    /* Hidden sibling "DIR/.rs-XXXXXX": same file system, so rename is atomic. */
    int fd = cli_temp_create(path, &o->tmp);
    if (fd < 0) {
        cli_error("%s: cannot create a temporary file next to it: %s", path, strerror(errno));
        free(o->path);
        o->path = NULL;
        return 1;
    }
    o->f = fdopen(fd, "wb");
    if (!o->f) {
        int e = errno;
        close(fd);
        cli_temp_remove(o->tmp);
        cli_error("%s: %s", path, strerror(e));
        free(o->path); free(o->tmp); o->path = o->tmp = NULL;
        return 1;
    }
    return 0;
}

void cli_out_abort(cli_out *o)
{
    if (o->f) fclose(o->f);
    cli_temp_remove(o->tmp);
    free(o->path);
    free(o->tmp);
    o->f = NULL;
    o->path = o->tmp = NULL;
}

int cli_out_finish(cli_out *o)
{
    if (!o->f) return 0;
    int bad = 0, e = 0;
    if (fflush(o->f) != 0 || ferror(o->f)) { bad = 1; e = errno; }
    if (!bad && fsync(fileno(o->f)) != 0 && errno != EINVAL) { bad = 1; e = errno; }
    if (fclose(o->f) != 0 && !bad) { bad = 1; e = errno; }
    o->f = NULL;
    if (bad) cli_error("%s: write failed: %s", o->path, strerror(e ? e : EIO));
    return bad;
}

static void sync_parent(const char *path)
{
    const char *slash = strrchr(path, '/');
    char *dir = dup_str(slash ? path : ".");
    if (!dir) return;
    if (slash) dir[slash - path + (slash == path)] = '\0';
    int fd = open(dir, O_RDONLY);
    if (fd >= 0) { (void)fsync(fd); close(fd); }
    free(dir);
}

int cli_out_commit_all(cli_out *const *outs, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (outs[i] && outs[i]->tmp && cli_out_finish(outs[i])) return 1;
    /* the last word on collisions: no rename replaces a file this run read */
    for (size_t i = 0; i < n; i++)
        if (outs[i] && outs[i]->tmp && cli_inputs_check_output(outs[i]->path, "the output")) return 1;
    /* Every output is complete: rename them all with the signals held, so
     * an interrupt cannot land between two renames. */
    sigset_t saved;
    signals_block(1, &saved);
    int bad = 0;
    for (size_t i = 0; i < n && !bad; i++) {
        cli_out *o = outs[i];
        if (!o || !o->tmp) continue;
        if (rename(o->tmp, o->path) != 0) {
            cli_error("%s: write failed: %s", o->path, strerror(errno));
            bad = 1;
            break;
        }
        cli_temp_forget(o->tmp);
        sync_parent(o->path); /* make the rename itself durable; best effort */
        free(o->path);
        free(o->tmp);
        o->path = o->tmp = NULL;
    }
    signals_block(0, &saved);
    return bad;
}

int cli_out_write_file(const char *path, const void *data, size_t size)
{
    cli_out out;
    memset(&out, 0, sizeof out);
    if (cli_out_open(&out, path)) return 1;
    if (fwrite(data, 1, size, out.f) != size) {
        cli_error("%s: write failed: %s", path, strerror(errno ? errno : EIO));
        cli_out_abort(&out);
        return 1;
    }
    return cli_out_commit(&out);
}

int cli_out_commit(cli_out *o)
{
    if (!o->f || !o->tmp) return 1;
    cli_out *one[1] = { o };
    if (cli_out_commit_all(one, 1)) {
        cli_out_abort(o);
        return 1;
    }
    return 0;
}

/* ---- output names ----------------------------------------------------------- */

/* "realpath(DIR)/BASE" of a path that need not exist yet; NULL when the
 * folder does not exist (cli_out_open reports that). */
static char *canonical_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    char *dir = dup_str(slash ? path : ".");
    if (!dir) return NULL;
    if (slash) dir[slash - path + (slash == path)] = '\0';
    char *real = realpath(dir, NULL);
    free(dir);
    if (!real) return NULL;
    size_t a = strlen(real), b = strlen(base);
    char *out = malloc(a + b + 2);
    if (out) {
        memcpy(out, real, a);
        out[a] = '/';
        memcpy(out + a + 1, base, b + 1);
    }
    free(real);
    return out;
}

int cli_check_outputs(const cli_file_role *outs, size_t nout, const cli_file_role *ins, size_t nin)
{
    for (size_t i = 0; i < nout; i++) {
        const char *p = outs[i].path;
        if (!p) continue;
        size_t n = strlen(p);
        if (n == 0) {
            cli_error("%s: the file name is empty", outs[i].role);
            return 1;
        }
        if (p[n - 1] == '/') {
            cli_error("%s: names a folder; the output must be a file", p);
            return 1;
        }
    }
    int rc = 0;
    char **canon = calloc(nout ? nout : 1, sizeof *canon);
    if (!canon) { cli_error("out of memory"); return 1; }
    for (size_t i = 0; i < nout && !rc; i++) {
        const char *p = outs[i].path;
        if (!p) continue;
        struct stat so;
        int exists = stat(p, &so) == 0;
        for (size_t j = 0; j < nin && exists && !rc; j++) {
            struct stat si;
            if (ins[j].path && stat(ins[j].path, &si) == 0 && si.st_dev == so.st_dev && si.st_ino == so.st_ino) {
                cli_error("%s: %s is also the %s (%s); refusing to overwrite an input", p, outs[i].role, ins[j].role,
                          ins[j].path);
                rc = 1;
            }
        }
        canon[i] = canonical_name(p);
        for (size_t j = 0; j < i && !rc; j++) {
            const char *q = outs[j].path;
            struct stat sq;
            int same = 0;
            if (!q) continue;
            if (exists && stat(q, &sq) == 0) same = sq.st_dev == so.st_dev && sq.st_ino == so.st_ino;
            if (!same && canon[i] && canon[j]) same = !strcmp(canon[i], canon[j]);
            if (!same) same = !strcmp(p, q);
            if (same) {
                cli_error("%s: given as both %s and %s; each output needs its own file", p, outs[j].role,
                          outs[i].role);
                rc = 1;
            }
        }
    }
    for (size_t i = 0; i < nout; i++) free(canon[i]);
    free(canon);
    return rc;
}

/* ---- DEM ------------------------------------------------------------------ */

/* An image read through OpenImageIO: a DEM (gray float) or a texture (RGBA8). */
typedef struct image_read {
    const char *path;  /* what OpenImageIO opens */
    const char *shown; /* the user's name for it, in messages */
    uint32_t max_side; /* DEM: largest side (0: none) */
    uint64_t max_pixels; /* texture: most pixels (0: none) */
    uint32_t *w, *h;
    float **z;
    uint8_t **rgba;
} image_read;

static int run_read(const image_read *r)
{
    if (r->z) return cli_image_read_gray_float(r->path, r->shown, r->max_side, r->w, r->h, r->z);
    return cli_image_read_rgba8(r->path, r->shown, r->max_pixels, r->w, r->h, r->rgba);
}

/* OpenImageIO 2.4 leaves libpng's default error handler in place, which
 * prints "libpng error: ..." on stderr before OpenImageIO reports the same
 * problem. Run the read with stderr sent to an unlinked temporary file and
 * pass on only our own "roadsplat: " lines, so a bad image still costs
 * exactly one line. Without a temporary file the read runs unfiltered. */
static int read_image_quietly(const image_read *r)
{
    fflush(stderr);
    FILE *cap = tmpfile();
    int saved = cap ? dup(2) : -1;
    if (saved < 0 || dup2(fileno(cap), 2) < 0) {
        if (saved >= 0) close(saved);
        if (cap) fclose(cap);
        return run_read(r);
    }
    int rc = run_read(r);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    rewind(cap);
    char buf[512];
    int at_start = 1, keep = 0, printed = 0;
    while (fgets(buf, sizeof buf, cap)) {
        if (at_start) keep = strncmp(buf, "roadsplat: ", 11) == 0;
        if (keep) { fputs(buf, stderr); printed = 1; }
        at_start = strchr(buf, '\n') != NULL;
    }
    fclose(cap);
    if (keep && !at_start) fputc('\n', stderr);
    if (rc && !printed) cli_error("%s: cannot read image", r->shown);
    return rc;
}

/* The first line that is not blank or a '#' comment starts with the
 * keyword "road" (docs/road-format.md), within the first n bytes. */
static int looks_like_roads(const char *p, size_t n)
{
    size_t i = 0;
    while (i < n) {
        while (i < n && (p[i] == ' ' || p[i] == '\t' || p[i] == '\r' || p[i] == '\n')) i++;
        if (i < n && p[i] == '#') {
            while (i < n && p[i] != '\n') i++;
            continue;
        }
        return n - i >= 5 && memcmp(p + i, "road", 4) == 0 && (p[i + 4] == ' ' || p[i + 4] == '\t');
    }
    return 0;
}

/* Inputs opened once (cli.h, cli_input). The open does not block (a FIFO
 * with no writer yet, a device whose open has effects); a pipe then waits
 * for its first bytes or its end before reading blocks again. */
int cli_input_open(cli_input *in, const char *path, int folder_ok)
{
    memset(in, 0, sizeof *in);
    in->path = path;
    in->fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (in->fd < 0) { cli_error("%s: %s", path, strerror(errno)); return 1; }
    if (fstat(in->fd, &in->st) != 0) {
        cli_error("%s: %s", path, strerror(errno));
        cli_input_close(in);
        return 1;
    }
    int dir = S_ISDIR(in->st.st_mode);
    if ((dir && !folder_ok) || (!dir && !S_ISREG(in->st.st_mode) && !S_ISFIFO(in->st.st_mode) &&
                                !S_ISSOCK(in->st.st_mode))) {
        cli_error("%s: %s; inputs must be regular files or pipes", path, dir ? "is a directory" : "is a device");
        cli_input_close(in);
        return 1;
    }
    if (dir) return 0;
    if (!S_ISREG(in->st.st_mode)) {
        struct pollfd p;
        p.fd = in->fd;
        p.events = POLLIN;
        while (poll(&p, 1, -1) < 0 && errno == EINTR) {}
    }
    int fl = fcntl(in->fd, F_GETFL);
    if (fl != -1) fcntl(in->fd, F_SETFL, fl & ~O_NONBLOCK);
    while (in->got < sizeof in->head) {
        ssize_t k = read(in->fd, in->head + in->got, sizeof in->head - in->got);
        if (k < 0 && errno == EINTR) continue;
        if (k < 0) {
            cli_error("%s: read error: %s", path, strerror(errno));
            cli_input_close(in);
            return 1;
        }
        if (k == 0) { in->eof = 1; break; }
        in->got += (size_t)k;
    }
    return 0;
}

void cli_input_close(cli_input *in)
{
    if (in->fd >= 0) close(in->fd);
    in->fd = -1;
    free(in->all);
    in->all = NULL;
}

int cli_input_read_all(cli_input *in, size_t limit, char **data, size_t *size)
{
    *data = NULL;
    *size = 0;
    if (in->all) { /* read before (a pipe): handed on */
        if (in->all_size > limit) {
            cli_error("%s: file is larger than the %zu-byte limit", in->path, limit);
            return 1;
        }
        *data = in->all;
        *size = in->all_size;
        in->all = NULL;
        return 0;
    }
    if (S_ISREG(in->st.st_mode) && (uint64_t)in->st.st_size > (uint64_t)limit) { /* before allocating */
        cli_error("%s: file is larger than the %zu-byte limit", in->path, limit);
        return 1;
    }
    /* a regular file from after its head, wherever an earlier reader left it */
    if (S_ISREG(in->st.st_mode) && lseek(in->fd, (off_t)in->got, SEEK_SET) < 0) {
        cli_error("%s: read error: %s", in->path, strerror(errno));
        return 1;
    }
    size_t cap = in->got + 1, n = in->got;
    if (S_ISREG(in->st.st_mode) && (uint64_t)in->st.st_size + 1 > cap) cap = (size_t)in->st.st_size + 1;
    if (!in->eof && cap < ((size_t)1 << 16)) cap = (size_t)1 << 16;
    char *buf = malloc(cap);
    if (!buf) { cli_error("%s: out of memory", in->path); return 1; }
    /* a DEM of a few MB: its pages in one call, not a fault per 4 KiB
     * page as read() fills them (~10 us each on the benchmark VMs) */
    if (cap >= PREFAULT_MIN) cli_prefault(buf, cap);
    memcpy(buf, in->head, in->got);
    while (!in->eof) {
        if (n + 1 >= cap) {
            if (n > limit) break;
            size_t nc = cap > SIZE_MAX / 2 ? SIZE_MAX : cap * 2;
            if (nc > limit + 2) nc = limit + 2;
            char *nb = nc > cap ? realloc(buf, nc) : NULL;
            if (!nb) { free(buf); cli_error("%s: out of memory", in->path); return 1; }
            buf = nb;
            cap = nc;
        }
        ssize_t k = read(in->fd, buf + n, cap - 1 - n);
        if (k < 0 && errno == EINTR) continue;
        if (k < 0) { free(buf); cli_error("%s: read error: %s", in->path, strerror(errno)); return 1; }
        if (k == 0) break;
        n += (size_t)k;
    }
    if (n > limit) {
        free(buf);
        cli_error("%s: file is larger than the %zu-byte limit", in->path, limit);
        return 1;
    }
    buf[n] = '\0';
    *data = buf;
    *size = n;
    return 0;
}

void cli_input_keep(cli_input *in, char *data, size_t size)
{
    free(in->all);
    in->all = data;
    in->all_size = size;
}

/* A name OpenImageIO can open for this input, naming the inode that was
 * opened (and is registered), never the path again: a regular file through
 * /dev/fd; a pipe's contents are first copied into an unlinked temporary
 * file (*keep, named through /dev/fd). */
static const char *input_for_image(cli_input *in, char *name, size_t name_size, FILE **keep)
{
    *keep = NULL;
    if (S_ISREG(in->st.st_mode)) {
        snprintf(name, name_size, "/dev/fd/%d", in->fd);
        return name;
    }
    char *data;
    size_t size;
    if (cli_input_read_all(in, (size_t)1 << 31, &data, &size)) return NULL;
    FILE *f = tmpfile();
    int ok = f && fwrite(data, 1, size, f) == size && fflush(f) == 0;
    free(data);
    if (!ok) {
        if (f) fclose(f);
        cli_error("%s: cannot copy the stream into a temporary file: %s", in->path, strerror(errno ? errno : EIO));
        return NULL;
    }
    *keep = f;
    snprintf(name, name_size, "/dev/fd/%d", fileno(f));
    return name;
}

/* Default library limits (the texture loader has no context). */
static void default_limits(rs_limits *lim)
{
    rs_ctx *c = NULL;
    memset(lim, 0, sizeof *lim);
    if (rs_ctx_create(NULL, NULL, &c) == RS_OK) rs_ctx_limits(c, lim);
    rs_ctx_free(c);
}

/* The pixels all decoded images (textures, the atlas, surface images) may
 * hold together, and what they hold so far. */
static uint64_t image_budget = CLI_IMAGE_BUDGET_DEFAULT, image_pixels;

void cli_image_budget_set(uint64_t pixels) { image_budget = pixels; }

/* A PNG's declared size from its IHDR (the first 24 bytes): 1, else 0. */
static int png_header_size(const char *p, size_t n, uint64_t *pixels)
{
    static const unsigned char sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
    const unsigned char *u = (const unsigned char *)p;
    if (n < 24 || memcmp(u, sig, 8) || memcmp(u + 12, "IHDR", 4)) return 0;
    uint64_t w = (uint64_t)u[16] << 24 | (uint64_t)u[17] << 16 | (uint64_t)u[18] << 8 | u[19];
    uint64_t h = (uint64_t)u[20] << 24 | (uint64_t)u[21] << 16 | (uint64_t)u[22] << 8 | u[23];
    *pixels = w * h;
    return 1;
}

static int over_budget(const char *path, uint64_t pixels)
{
    if (!image_budget || pixels <= image_budget - (image_pixels < image_budget ? image_pixels : image_budget))
        return 0;
    cli_error("%s: its %llu pixels would bring the decoded images of this run to %llu pixels, over the budget of "
              "%llu (--max-image-pixels N raises it)", path, (unsigned long long)pixels,
              (unsigned long long)(image_pixels + pixels), (unsigned long long)image_budget);
    return 1;
}

int cli_load_texture(const char *path, const char *role, uint32_t *w, uint32_t *h, uint8_t **rgba)
{
    cli_input in;
    *rgba = NULL;
    if (cli_input_open(&in, path, 0)) return 1;
    rs_limits lim;
    default_limits(&lim);
    uint64_t declared;
    /* before decoding (one image over its own limit gets that message) */
    if (png_header_size(in.head, in.got, &declared) &&
        (!lim.max_texture_pixels || declared <= lim.max_texture_pixels) && over_budget(path, declared)) {
        cli_input_close(&in);
        return 1;
    }
    char name[64];
    FILE *keep;
    const char *p = input_for_image(&in, name, sizeof name, &keep);
    int bad = !p || (role && cli_inputs_add(path, role, keep ? fileno(keep) : in.fd, NULL, 0));
    if (bad) {
        if (keep) fclose(keep);
        cli_input_close(&in);
        return 1;
    }
    image_read r = { p, path, 0, lim.max_texture_pixels, w, h, NULL, rgba };
    int rc = read_image_quietly(&r);
    if (keep) fclose(keep);
    cli_input_close(&in);
    if (!rc && over_budget(path, (uint64_t)*w * *h)) { /* formats whose size was not read above */
        free(*rgba);
        *rgba = NULL;
        return 1;
    }
    if (!rc) image_pixels += (uint64_t)*w * *h;
    return rc;
}

rs_dem *cli_load_dem(rs_ctx *ctx, const char *path)
{
    cli_input in;
    if (cli_input_open(&in, path, 0)) return NULL;
    return cli_load_dem_input(ctx, &in);
}

rs_dem *cli_load_dem_input(rs_ctx *ctx, cli_input *inp)
{
    cli_input in = *inp; /* ours now: closed on every path */
    const char *path = in.path;
    inp->fd = -1;
    inp->all = NULL;
    rs_dem *dem = NULL;
    /* DEM and ROADS swapped on the command line: say so, rather than pass a
     * text file to OpenImageIO ("could not find a format reader"). */
    if (looks_like_roads(in.head, in.got)) {
        cli_input_close(&in);
        cli_error("%s: this is a road file, not a DEM (arguments in the wrong order?)", path);
        return NULL;
    }
    /* A .pgm name goes to our reader even with a wrong magic, for its message. */
    size_t pl = strlen(path);
    int pgm_name = pl >= 4 && path[pl - 4] == '.' && (path[pl - 3] | 0x20) == 'p' && (path[pl - 2] | 0x20) == 'g' &&
                   (path[pl - 1] | 0x20) == 'm';
    if (pgm_name || (in.got >= 2 && in.head[0] == 'P' && (in.head[1] == '2' || in.head[1] == '5'))) {
        /* The header first: a DEM over the limits is refused from the first
         * 4 KiB, before the rest of the file is read. A parse of that prefix
         * only counts when it is the whole file (or the limit is the error). */
        rs_result rc = rs_dem_parse_pgm(ctx, in.head, in.got, &dem);
        if (rc == RS_ERR_LIMIT || in.eof) {
            int bad = rc == RS_OK && cli_inputs_add(path, "DEM", in.fd, in.head, in.got);
            cli_input_close(&in);
            if (rc != RS_OK) {
                cli_error("%s: %s", path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(rc));
                return NULL;
            }
            if (bad) {
                rs_dem_free(ctx, dem);
                return NULL;
            }
            return dem;
        }
        rs_dem_free(ctx, dem);
        dem = NULL;
        /* Large enough for any DEM within the default limits, even as P2. */
        size_t limit = SIZE_MAX > 0xFFFFFFFFu ? (size_t)1 << 33 : (size_t)1 << 30;
        char *data;
        size_t size;
        int bad = cli_input_read_all(&in, limit, &data, &size);
        bad = bad || cli_inputs_add(path, "DEM", in.fd, data, size);
        cli_input_close(&in);
        if (bad) {
            free(data);
            return NULL;
        }
        rc = rs_dem_parse_pgm(ctx, data, size, &dem);
        free(data);
        if (rc != RS_OK) {
            cli_error("%s: %s", path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(rc));
            return NULL;
        }
        return dem;
    }
    char name[64];
    FILE *keep;
    const char *p = input_for_image(&in, name, sizeof name, &keep);
    int reg_bad = !p || cli_inputs_add(path, "DEM", keep ? fileno(keep) : in.fd, NULL, 0);
    if (reg_bad) {
        if (keep) fclose(keep);
        cli_input_close(&in);
        return NULL;
    }
    uint32_t w, h;
    float *z;
    rs_limits lim = { 0 };
    rs_ctx_limits(ctx, &lim);
    image_read r = { p, path, lim.max_dem_side, 0, &w, &h, &z, NULL };
    int bad = read_image_quietly(&r);
    if (keep) fclose(keep);
    cli_input_close(&in);
    if (bad) return NULL;
    rs_result rc = rs_dem_create(ctx, w, h, z, &dem);
    free(z);
    if (rc != RS_OK) {
        cli_error("%s: %s", path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(rc));
        return NULL;
    }
    return dem;
}
