/*
 * test_conf.c - the configuration parser (sim/conf.c), the sim's tables
 * (sim/ocean_conf.c), the shipped config/oceand.conf and scenes, and the
 * fuzz seed corpus (run through the fuzz target's own checks).
 *
 * Runs from the repository root (paths config/... and tests/fuzz/...).
 */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmocka.h>

#include "conf.h"
#include "ocean.h"
#include "ocean_conf.h"
#include "spectrum.h"

/* The fuzz target's checks and its every-type table (fuzz_kit). */
#define FUZZ_CONF_NO_MAIN
#include "fuzz/fuzz_conf.c"

#define CORPUS "tests/fuzz/corpus_conf"

static char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap + 1);
    size_t k;
    while (buf && (k = fread(buf + n, 1, cap - n, f)) > 0) {
        n += k;
        if (n == cap) {
            char *nb = realloc(buf, 2 * cap + 1);
            if (!nb) { free(buf); buf = NULL; break; }
            buf = nb;
            cap *= 2;
        }
    }
    fclose(f);
    if (buf) buf[n] = '\0';
    *len = n;
    return buf;
}

static conf_set kit_set(fuzz_kit *k, const conf_table **t, void **g)
{
    t[0] = &fuzz_kit_table;
    g[0] = k;
    return (conf_set){t, g, 1};
}

/* Loads text into a kit on top of its defaults. */
static ocean_result load_kit(const char *text, fuzz_kit *k, char *err, size_t errlen)
{
    const conf_table *t[1];
    void *g[1];
    conf_set set = kit_set(k, t, g);
    return conf_load_string("kit.conf", text, strlen(text), &set, NULL, err, errlen);
}

/* ---- tables ---------------------------------------------------------------- */

static void test_tables_check(void **state)
{
    (void)state;
    char err[512] = "";
    ocean_params p;
    ocean_scene s;
    fuzz_kit k;
    const conf_table *t[] = {ocean_conf_table(), ocean_conf_scene_table(), &fuzz_kit_table};
    void *g[] = {&p, &s, &k};
    conf_set set = {t, g, 3};
    assert_int_equal(conf_set_check(&set, err, sizeof err), OCEAN_OK);
    assert_string_equal(err, "");

    /* A broken table is caught: a key twice across the set. */
    const conf_table *t2[] = {ocean_conf_table(), ocean_conf_table()};
    void *g2[] = {&p, &p};
    conf_set twice = {t2, g2, 2};
    assert_int_equal(conf_set_check(&twice, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "key defined twice: 'sea.spectrum'"));

    /* A default outside its own range is caught. */
    conf_entry bad = fuzz_kit_entries[0];
    bad.def = "101";
    conf_table bt = {"bad", "bad", &bad, 1, sizeof(fuzz_kit)};
    const conf_table *t3[] = {&bt};
    void *g3[] = {&k};
    conf_set bs = {t3, g3, 1};
    assert_int_equal(conf_set_check(&bs, err, sizeof err), OCEAN_EINVAL);
    assert_non_null(strstr(err, "bad default in table bad: kit.int: out of range [-100, 100]: '101'"));
}

static void test_defaults_match_ocean_params_default(void **state)
{
    (void)state;
    ocean_params want, got;
    char err[512];
    ocean_params_default(&want);
    /* Start from garbage: a field the table misses stays garbage and fails. */
    memset(&got, 0xA5, sizeof got);
    const conf_table *t[] = {ocean_conf_table()};
    void *g[] = {&got};
    conf_set set = {t, g, 1};
    assert_int_equal(conf_defaults(&set, err, sizeof err), OCEAN_OK);

    assert_int_equal(got.sea.spectrum, want.sea.spectrum);
    assert_int_equal(got.sea.spreading, want.sea.spreading);
    assert_true(got.sea.wind_u10 == want.sea.wind_u10);
    assert_true(got.sea.wind_dir_deg == want.sea.wind_dir_deg);
    assert_true(got.sea.fetch_m == want.sea.fetch_m);
    assert_true(got.sea.depth_m == want.sea.depth_m);
    assert_true(got.sea.swell == want.sea.swell);
    assert_true(got.sea.phillips_a == want.sea.phillips_a);
    assert_true(got.sea.small_wave_m == want.sea.small_wave_m);
    assert_true(got.sea.choppiness == want.sea.choppiness);
    assert_int_equal(got.sea.whitecaps, want.sea.whitecaps);
    got.sea.unused_ = 0; /* no key */
    assert_true(got.seed == want.seed);
    assert_int_equal(got.n, want.n);
    assert_int_equal(got.cascades, want.cascades);
    assert_true(got.patch_m == want.patch_m);
    assert_true(got.cascade_ratio == want.cascade_ratio);
    assert_true(got.k_max == want.k_max);
    assert_int_equal(got.threads, want.threads);
    assert_int_equal(got.plan_measure, want.plan_measure);
    assert_string_equal(got.wisdom, want.wisdom);
    /* And nothing else differs (ocean_params has no padding to hide in). */
    assert_memory_equal(&got, &want, sizeof got);
    assert_int_equal(ocean_params_validate(&got, err, sizeof err), OCEAN_OK);

    /* ocean_conf_load_string of nothing gives the same. */
    memset(&got, 0, sizeof got);
    assert_int_equal(ocean_conf_load_string("empty", "", 0, &got, err, sizeof err), OCEAN_OK);
    assert_memory_equal(&got, &want, sizeof got);
}

/* ---- every type ---------------------------------------------------------------- */

static void test_types_parse(void **state)
{
    (void)state;
    fuzz_kit k;
    char err[512] = "";
    const conf_table *t[1];
    void *g[1];
    conf_set set = kit_set(&k, t, g);
    memset(&k, 0, sizeof k);
    assert_int_equal(conf_defaults(&set, err, sizeof err), OCEAN_OK);
    assert_int_equal(k.i, 7);
    assert_true(k.u == 16);
    assert_true(k.d == 0.1);
    assert_true(isinf(k.k) && k.k > 0);
    assert_int_equal(k.b, 0);
    assert_string_equal(k.s, "hi");
    assert_int_equal(k.e, 2);
    assert_int_equal(k.f, 1u | 4u);

    const char *text =
        "# whole-line comment\n"
        "\n"
        "   \t  \n"
        "kit.int = -42          # trailing comment\n"
        "kit.u64=18446744073709551615\n"
        "\tkit.double\t=\t-2.5e2\t\n"
        "kit.k = 0\n"
        "kit.bool = ON\n"
        "kit.str = a b#c\n"
        "kit.enum = Blue\n"
        "kit.flags = d , b\n"
        "kit.twice = 21\n";
    assert_int_equal(load_kit(text, &k, err, sizeof err), OCEAN_OK);
    assert_int_equal(k.i, -42);
    assert_true(k.u == UINT64_MAX);
    assert_true(k.d == -250.0);
    assert_true(k.k == 0.0);
    assert_int_equal(k.b, 1);
    assert_string_equal(k.s, "a b"); /* '#' starts a comment */
    assert_int_equal(k.e, 7);
    assert_int_equal(k.f, 64u | 2u);
    assert_int_equal(k.derived, 42); /* set by kit.twice's hook */

    /* Quoted strings keep '#', blanks and escapes; alias names; hex; inf. */
    assert_int_equal(load_kit("kit.str = \" #\\\"q\\\\ \"  # c\n"
                              "kit.enum = crimson\nkit.u64 = 0xFf\nkit.k = Infinity\n"
                              "kit.flags = all\nkit.int = +100\nkit.double = .5\n",
                              &k, err, sizeof err),
                     OCEAN_OK);
    assert_string_equal(k.s, " #\"q\\ ");
    assert_int_equal(k.e, 1);
    assert_true(k.u == 255);
    assert_true(isinf(k.k));
    assert_int_equal(k.f, 1u | 2u | 4u | 64u);
    assert_int_equal(k.i, 100);
    assert_true(k.d == 0.5);

    /* Empty string, none, exactly 15 bytes, UTF-8 text, CRLF, BOM, no final newline. */
    assert_int_equal(load_kit("\xEF\xBB\xBFkit.str =\r\nkit.flags = none\r\nkit.derived = 5", &k, err,
                              sizeof err),
                     OCEAN_OK);
    assert_string_equal(k.s, "");
    assert_int_equal(k.f, 0);
    assert_int_equal(k.derived, 5);
    assert_int_equal(load_kit("kit.str = 0123456789abcde\n", &k, err, sizeof err), OCEAN_OK);
    assert_string_equal(k.s, "0123456789abcde");
    assert_int_equal(load_kit("kit.str = caf\xC3\xA9 \xF0\x9F\x8C\x8A\n", &k, err, sizeof err), OCEAN_OK);
    assert_string_equal(k.s, "caf\xC3\xA9 \xF0\x9F\x8C\x8A");
}

static void test_bool_spellings(void **state)
{
    (void)state;
    static const char *const yes[] = {"on", "true", "yes", "1", "TRUE", "Yes"};
    static const char *const no[] = {"off", "false", "no", "0", "OFF", "No"};
    fuzz_kit k;
    char err[512], line[64];
    for (size_t i = 0; i < 6; i++) {
        snprintf(line, sizeof line, "kit.bool = %s\n", yes[i]);
        assert_int_equal(load_kit(line, &k, err, sizeof err), OCEAN_OK);
        assert_int_equal(k.b, 1);
        snprintf(line, sizeof line, "kit.bool = %s\n", no[i]);
        assert_int_equal(load_kit(line, &k, err, sizeof err), OCEAN_OK);
        assert_int_equal(k.b, 0);
    }
}

/* ---- errors ------------------------------------------------------------------------ */

typedef struct err_case {
    const char *text;
    size_t len;          /* 0: strlen */
    ocean_result code;
    const char *want;    /* exact substring, "kit.conf:N: ... 'text'" */
} err_case;

static void test_errors(void **state)
{
    (void)state;
    static const err_case cases[] = {
        {"kit.nope = 1\n", 0, OCEAN_EFORMAT, "kit.conf:1: unknown key: 'kit.nope'"},
        {"kit.itn = 1\n", 0, OCEAN_EFORMAT, "kit.conf:1: unknown key (did you mean 'kit.int'?): 'kit.itn'"},
        {"\n\nkit.int 5\n", 0, OCEAN_EFORMAT, "kit.conf:3: missing '=' (expected key = value): 'kit.int 5'"},
        {"kit.int\n", 0, OCEAN_EFORMAT, "kit.conf:1: missing '=' (expected key = value): 'kit.int'"},
        {"= 5\n", 0, OCEAN_EFORMAT, "kit.conf:1: missing key before '=': '= 5'"},
        {"kit..int = 5\n", 0, OCEAN_EFORMAT, "kit.conf:1: bad key"},
        {"Kit.int = 5\n", 0, OCEAN_EFORMAT, "'Kit.int'"},
        {"kit.int = 12x\n", 0, OCEAN_EFORMAT, "kit.conf:1: kit.int: trailing text after the integer: '12x'"},
        {"kit.int = x12\n", 0, OCEAN_EFORMAT, "kit.conf:1: kit.int: not an integer: 'x12'"},
        {"kit.int = 1e2\n", 0, OCEAN_EFORMAT, "kit.int: trailing text after the integer: '1e2'"},
        {"kit.int = 101\n", 0, OCEAN_EINVAL, "kit.conf:1: kit.int: out of range [-100, 100]: '101'"},
        {"kit.int = -101\n", 0, OCEAN_EINVAL, "kit.int: out of range [-100, 100]: '-101'"},
        {"kit.int = 9223372036854775808\n", 0, OCEAN_EINVAL, "kit.int: out of range"},
        {"kit.int =\n", 0, OCEAN_EFORMAT, "kit.conf:1: kit.int: missing value: ''"},
        {"kit.int = # nothing\n", 0, OCEAN_EFORMAT, "kit.int: missing value"},
        {"kit.double = 1000.5\n", 0, OCEAN_EINVAL, "kit.conf:1: kit.double: out of range [-1000, 1000] m: '1000.5'"},
        {"kit.double = nan\n", 0, OCEAN_EFORMAT, "kit.double: NaN and infinity are not allowed: 'nan'"},
        {"kit.double = -NaN\n", 0, OCEAN_EFORMAT, "kit.double: NaN and infinity are not allowed: '-NaN'"},
        {"kit.double = inf\n", 0, OCEAN_EFORMAT, "kit.double: NaN and infinity are not allowed: 'inf'"},
        {"kit.double = 1e400\n", 0, OCEAN_EINVAL, "kit.double: too large for a double"},
        {"kit.double = 0x10\n", 0, OCEAN_EFORMAT, "kit.double: trailing text after the number: '0x10'"},
        {"kit.double = 1.2.3\n", 0, OCEAN_EFORMAT, "kit.double: not a number: '1.2.3'"},
        {"kit.double = 3 m\n", 0, OCEAN_EFORMAT, "kit.double: trailing text after the number: '3 m'"},
        {"kit.double = ten\n", 0, OCEAN_EFORMAT, "kit.double: not a number: 'ten'"},
        {"kit.k = -inf\n", 0, OCEAN_EFORMAT, "kit.k: NaN and infinity are not allowed: '-inf'"},
        {"kit.k = nan\n", 0, OCEAN_EFORMAT, "kit.k: NaN and infinity are not allowed"},
        {"kit.u64 = -1\n", 0, OCEAN_EFORMAT, "kit.u64: not an unsigned integer: '-1'"},
        {"kit.u64 = 18446744073709551616\n", 0, OCEAN_EINVAL, "kit.u64: out of range [0, 18446744073709551615]"},
        {"kit.u64 = 0x\n", 0, OCEAN_EFORMAT, "kit.u64: not an unsigned integer: '0x'"},
        {"kit.u64 = 0xfg\n", 0, OCEAN_EFORMAT, "kit.u64: trailing text after the integer: '0xfg'"},
        {"kit.u64 = 1 2\n", 0, OCEAN_EFORMAT, "kit.u64: trailing text after the integer: '1 2'"},
        {"kit.bool = maybe\n", 0, OCEAN_EFORMAT, "kit.bool: not a boolean (on/off, true/false, yes/no, 1/0): 'maybe'"},
        {"kit.bool = 2\n", 0, OCEAN_EFORMAT, "kit.bool: not a boolean"},
        {"kit.enum = purple\n", 0, OCEAN_EFORMAT, "kit.enum: unknown name (one of red, green, blue, crimson): 'purple'"},
        {"kit.flags = a,e\n", 0, OCEAN_EFORMAT, "kit.flags: unknown name in the list (names: a, b, c, d; or, alone, none or all): 'e'"},
        {"kit.flags = a,,b\n", 0, OCEAN_EFORMAT, "kit.flags: empty item in the list: ''"},
        {"kit.flags = a,\n", 0, OCEAN_EFORMAT, "kit.flags: empty item in the list"},
        {"kit.flags = a, b ,A\n", 0, OCEAN_EFORMAT, "kit.flags: listed twice: 'A'"},
        {"kit.str = 0123456789abcdef\n", 0, OCEAN_ETOOBIG, "kit.str: string too long (16 bytes, at most 15): '0123456789abcdef'"},
        {"kit.str = \"abc\n", 0, OCEAN_EFORMAT, "kit.conf:1: unterminated quoted value: '\"abc'"},
        {"kit.str = \"a\\tb\"\n", 0, OCEAN_EFORMAT, "bad escape in quoted value (only \\\" and \\\\): '\\t'"},
        {"kit.str = \"a\" b\n", 0, OCEAN_EFORMAT, "trailing text after the quoted value: 'b'"},
        {"kit.int = \"5\"\n", 0, OCEAN_EFORMAT, "kit.int: quotes are only for string values: '5'"},
        {"kit.int = 1\nkit.bool = on\nkit.int = 2\n", 0, OCEAN_EFORMAT, "kit.conf:3: duplicate key (first set on line 1): 'kit.int'"},
        {"kit.twice = 3\nkit.derived = 4\n", 0, OCEAN_EINVAL, "kit.conf:2: kit.derived conflicts with kit.twice on line 1; give one of them: 'kit.derived'"},
        {"kit.twice = 13\n", 0, OCEAN_EINVAL, "kit.conf:1: kit.twice: 13 is refused by the hook: '13'"},
        {"kit.int = 1\x01\n", 0, OCEAN_EFORMAT, "kit.conf:1: control character 0x01 at column 12: 'kit.int = 1\\x01'"},
        {"kit.int = 1\x7F\n", 0, OCEAN_EFORMAT, "control character 0x7F at column 12"},
        {"kit.int = 1\n\nkit.str = a\0b\n", 28, OCEAN_EFORMAT, "kit.conf:3: control character 0x00 at column 12: 'kit.str = a\\x00b'"},
        {"kit.int = 1\rkit.int = 2\n", 0, OCEAN_EFORMAT, "control character 0x0D at column 12"},
        {"kit.str = \xFF\n", 0, OCEAN_EFORMAT, "kit.conf:1: invalid UTF-8 at column 11: 'kit.str = \\xFF'"},
        {"kit.str = \xC0\xAF\n", 0, OCEAN_EFORMAT, "invalid UTF-8 at column 11"},          /* overlong '/' */
        {"kit.str = \xED\xA0\x80\n", 0, OCEAN_EFORMAT, "invalid UTF-8 at column 11"},      /* surrogate */
        {"kit.str = \xE2\x82\n", 0, OCEAN_EFORMAT, "invalid UTF-8 at column 11"},          /* cut short */
        {"kit.str = \xF4\x90\x80\x80\n", 0, OCEAN_EFORMAT, "invalid UTF-8 at column 11"},  /* > U+10FFFF */
        {"# \xEF\xBB\xBF a BOM inside is just text\nkit.int = 1\n\xEF\xBB\xBFkit.int = 2\n", 0, OCEAN_EFORMAT,
         "kit.conf:3: bad key (lower-case words of a-z, 0-9, '_', '-' joined by '.'): '\\uFEFFkit.int'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const err_case *c = &cases[i];
        fuzz_kit k, before;
        char err[512] = "";
        memset(&k, 0x3C, sizeof k);
        memcpy(&before, &k, sizeof k);
        const conf_table *t[1];
        void *g[1];
        conf_set set = kit_set(&k, t, g);
        size_t len = c->len ? c->len : strlen(c->text);
        ocean_result r = conf_load_string("kit.conf", c->text, len, &set, NULL, err, sizeof err);
        if (r != c->code || !strstr(err, c->want))
            print_error("case %zu: got %d '%s', want %d '%s'\n", i, (int)r, err, (int)c->code, c->want);
        assert_int_equal(r, c->code);
        assert_non_null(strstr(err, c->want));
        assert_memory_equal(&k, &before, sizeof k); /* all or nothing */
    }
}

static void test_long_line_and_file(void **state)
{
    (void)state;
    fuzz_kit k;
    char err[512];
    char *text = malloc(CONF_MAX_FILE + 64);
    assert_non_null(text);
    /* A line of exactly CONF_MAX_LINE bytes is fine; one more is not. */
    size_t n = (size_t)snprintf(text, 64, "kit.int = 1\n#");
    memset(text + n, 'x', CONF_MAX_LINE - 1);
    strcpy(text + n + CONF_MAX_LINE - 1, "\n");
    assert_int_equal(load_kit(text, &k, err, sizeof err), OCEAN_OK);
    memset(text + n, 'x', CONF_MAX_LINE);
    strcpy(text + n + CONF_MAX_LINE, "\n");
    assert_int_equal(load_kit(text, &k, err, sizeof err), OCEAN_ETOOBIG);
    assert_non_null(strstr(err, "kit.conf:2: line too long (1025 bytes, at most 1024): '#xxxx"));
    assert_non_null(strstr(err, "...'")); /* the text is cut, not dumped whole */
    assert_true(strlen(err) < 200);

    /* A source over CONF_MAX_FILE is refused as a whole. */
    memset(text, '\n', CONF_MAX_FILE + 1);
    const conf_table *t[1];
    void *g[1];
    conf_set set = kit_set(&k, t, g);
    assert_int_equal(conf_load_string("big.conf", text, CONF_MAX_FILE + 1, &set, NULL, err, sizeof err),
                     OCEAN_ETOOBIG);
    assert_non_null(strstr(err, "big.conf: file too large"));
    assert_int_equal(conf_load_string("big.conf", text, CONF_MAX_FILE, &set, NULL, err, sizeof err),
                     OCEAN_OK);

    char path[] = "/tmp/test_conf_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *f = fdopen(fd, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, CONF_MAX_FILE + 1, f), CONF_MAX_FILE + 1);
    fclose(f);
    assert_int_equal(conf_load_file(path, &set, NULL, err, sizeof err), OCEAN_ETOOBIG);
    assert_non_null(strstr(err, "file too large"));
    unlink(path);
    free(text);

    /* Missing file and a directory: EIO naming the path. */
    assert_int_equal(conf_load_file("tests/no/such.conf", &set, NULL, err, sizeof err), OCEAN_EIO);
    assert_non_null(strstr(err, "tests/no/such.conf: cannot open: "));
    assert_int_equal(conf_load_file("config", &set, NULL, err, sizeof err), OCEAN_EIO);
    assert_non_null(strstr(err, "config: cannot"));

    /* A tiny message buffer is cut, never overrun. */
    char tiny[8];
    memset(tiny, 'z', sizeof tiny);
    assert_int_equal(load_kit("kit.nope = 1\n", &k, tiny, sizeof tiny), OCEAN_EFORMAT);
    assert_string_equal(tiny, "kit.con");
}

/* ---- the sim's tables -------------------------------------------------------------- */

static void test_ocean_errors(void **state)
{
    (void)state;
    ocean_params p, def;
    char err[512];
    ocean_params_default(&def);
    static const struct { const char *text; const char *want; } cases[] = {
        {"sea.wind = 100.5\n", "in.conf:1: sea.wind: out of range [0, 100] m/s: '100.5'"},
        {"sea.direction = 361\n", "sea.direction: out of range [-360, 360] degrees"},
        {"sea.fetch = 0.5\n", "sea.fetch: out of range [1, 10000000] m"},
        {"sea.depth = 0\n", "sea.depth: out of range [0.01, 12000] m"},
        {"sea.swell = 11\n", "sea.swell: out of range [0, 10]"},
        {"sea.choppiness = -1\n", "sea.choppiness: out of range [0, 10]"},
        {"sea.beaufort = 13\n", "sea.beaufort: out of range [0, 12]: '13'"},
        {"ocean.n = 4096\n", "ocean.n: out of range [8, 2048]"},
        {"ocean.n = 4\n", "ocean.n: out of range [8, 2048]"},
        {"ocean.n = 384\n", "in.conf:1: ocean.n: must be a power of two (8, 16, ..., 2048): '384'"},
        {"ocean.cascades = 5\n", "ocean.cascades: out of range [1, 4]"},
        {"ocean.patch = 0.5\n", "ocean.patch: out of range [1, 100000] m"},
        {"ocean.cascade_ratio = 1.4\n", "ocean.cascade_ratio: out of range [1.5, 100]"},
        {"ocean.threads = 0\n", "ocean.threads: out of range [1, 64]"},
        {"ocean.k_max = 0\n", "ocean.k_max: out of range"},
        {"ocean.plan = patient\n", "ocean.plan: unknown name (one of estimate, measure, wisdom): 'patient'"},
        {"sea.spectrum = jonswap\nsea.spreading = cosine\n", "in.conf:2: sea.spreading: unknown name"},
        {"sea.beaufort = 3\nsea.wind = 4\n", "in.conf:2: sea.wind conflicts with sea.beaufort on line 1"},
        {"sea.wind = 3\nsea.beaufort = 4\n", "in.conf:2: sea.beaufort conflicts with sea.wind on line 1"},
        {"serve.port = 1\n", "in.conf:1: unknown key: 'serve.port'"},
        {"sea.wind = 5\nsea.wind = 5\n", "in.conf:2: duplicate key (first set on line 1): 'sea.wind'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        memcpy(&p, &def, sizeof p);
        p.n = 64; /* a non-default value that must survive a failed load */
        ocean_result r = ocean_conf_load_string("in.conf", cases[i].text, strlen(cases[i].text), &p, err,
                                                sizeof err);
        if (r == OCEAN_OK || !strstr(err, cases[i].want))
            print_error("case %zu: got '%s', want '%s'\n", i, err, cases[i].want);
        assert_int_not_equal(r, OCEAN_OK);
        assert_non_null(strstr(err, cases[i].want));
        assert_int_equal(p.n, 64);
    }
    /* Beaufort sets the wind, from the lead's table of forces. */
    for (int force = 0; force <= 12; force++) {
        char text[64];
        double u10;
        /* a patch that holds force 12's 1.07 km peak (ocean_plan.h) */
        snprintf(text, sizeof text, "sea.beaufort = %d\nocean.patch = 2000\n", force);
        assert_int_equal(ocean_conf_load_string("in.conf", text, strlen(text), &p, err, sizeof err), OCEAN_OK);
        assert_int_equal(ocean_beaufort_wind(force, &u10), OCEAN_OK);
        assert_true(p.sea.wind_u10 == u10);
    }
    assert_true(p.sea.wind_u10 == 35.0);
    /* server.* and scene.* belong to other readers: skipped, but still syntax-checked. */
    const char *mixed = "server.port = 8080\nscene.name = x\nsea.wind = 7\n";
    assert_int_equal(ocean_conf_load_string("in.conf", mixed, strlen(mixed), &p, err, sizeof err), OCEAN_OK);
    assert_true(p.sea.wind_u10 == 7.0);
    const char *badsyntax = "server.port 8080\n";
    assert_int_equal(ocean_conf_load_string("in.conf", badsyntax, strlen(badsyntax), &p, err, sizeof err),
                     OCEAN_EFORMAT);
    assert_non_null(strstr(err, "in.conf:1: missing '='"));
}

static void test_shipped_config(void **state)
{
    (void)state;
    ocean_params p, def;
    char err[512] = "";
    ocean_params_default(&def);
    memset(&p, 0, sizeof p);
    ocean_result r = ocean_conf_load("config/oceand.conf", &p, err, sizeof err);
    if (r != OCEAN_OK) print_error("%s\n", err);
    assert_int_equal(r, OCEAN_OK);
    /* The shipped file states the defaults: loading it changes nothing. */
    assert_memory_equal(&p, &def, sizeof p);

    /* Every key is in the file with its default (optional keys commented). */
    size_t len;
    char *text = read_all("config/oceand.conf", &len);
    assert_non_null(text);
    const conf_table *tab = ocean_conf_table();
    for (size_t i = 0; i < tab->count; i++) {
        const conf_entry *e = &tab->entries[i];
        char want[128];
        if (e->flags & CONF_F_NOSTORE)
            snprintf(want, sizeof want, "\n# %s = ", e->name);
        else
            snprintf(want, sizeof want, "\n%s = %s\n", e->name, e->def);
        if (!strstr(text, want)) print_error("config/oceand.conf lacks '%s'\n", want + 1);
        assert_non_null(strstr(text, want));
    }
    /* The daemon's section is marked. */
    assert_non_null(strstr(text, "# ---- BEGIN server.* ----"));
    assert_non_null(strstr(text, "# ---- END server.* ----"));

    /* Loaded with the daemon's layout (ocean table + the daemon's table in
     * one set), a server.* key goes to the other table.  A probe key stands
     * in for the daemon's table, whose keys the daemon adds to the file;
     * the rest of server.* is skipped here. */
    typedef struct { int probe; } fake_server;
    static const conf_entry fe[] = {{.name = "server.conf_test_probe", .type = CONF_INT, .offset = 0,
                                     .min = 1, .max = 65535, .def = "8080", .help = "probe"}};
    static const conf_table ft = {"server", "daemon", fe, 1, sizeof(fake_server)};
    static const char *const skip[] = {"server", NULL};
    conf_load_opts opts = {0, skip};
    fake_server srv = {0};
    const conf_table *t[] = {ocean_conf_table(), &ft};
    void *g[] = {&p, &srv};
    conf_set set = {t, g, 2};
    assert_int_equal(conf_set_check(&set, err, sizeof err), OCEAN_OK);
    r = conf_load_file("config/oceand.conf", &set, &opts, err, sizeof err);
    if (r != OCEAN_OK) print_error("%s\n", err);
    assert_int_equal(r, OCEAN_OK);
    assert_int_equal(srv.probe, 8080);
    assert_memory_equal(&p, &def, sizeof p);
    char *with = malloc(len + 64);
    assert_non_null(with);
    memcpy(with, text, len);
    strcpy(with + len, "server.conf_test_probe = 9000\n");
    assert_int_equal(conf_load_string("with", with, strlen(with), &set, &opts, err, sizeof err), OCEAN_OK);
    assert_int_equal(srv.probe, 9000);
    assert_memory_equal(&p, &def, sizeof p);
    free(with);
    free(text);
}

static void test_shipped_scenes(void **state)
{
    (void)state;
    static const char *const need[] = {"flight", "ship-bridge", "harbour", "storm"};
    ocean_params def;
    ocean_params_default(&def);
    DIR *d = opendir("config/scenes");
    assert_non_null(d);
    struct dirent *de;
    int found[4] = {0, 0, 0, 0}, count = 0;
    while ((de = readdir(d)) != NULL) {
        size_t n = strlen(de->d_name);
        if (n < 6 || strcmp(de->d_name + n - 5, ".conf") != 0) continue;
        char path[512], err[512] = "";
        snprintf(path, sizeof path, "config/scenes/%s", de->d_name);
        ocean_scene s;
        memset(&s, 0, sizeof s);
        ocean_result r = ocean_conf_scene_load(path, &def, &s, err, sizeof err);
        if (r != OCEAN_OK) print_error("%s\n", err);
        assert_int_equal(r, OCEAN_OK);
        count++;
        /* The name is the file's name; every scene declares effects, a
         * description and a usable camera hint, and makes a valid ocean. */
        assert_int_equal(strlen(s.name), n - 5);
        assert_memory_equal(s.name, de->d_name, n - 5);
        assert_true(s.effects != 0 && (s.effects & ~OCEAN_SCENE_FX_ALL) == 0);
        assert_true(strlen(s.description) > 10);
        double cam[5];
        assert_int_equal(ocean_conf_camera_hint_parse(s.camera_hint, cam), OCEAN_OK);
        assert_true(cam[1] > 0.0); /* above the sea */
        assert_int_equal(ocean_params_validate(&s.params, err, sizeof err), OCEAN_OK);

        for (int i = 0; i < 4; i++)
            if (strcmp(s.name, need[i]) == 0) found[i] = 1;
        /* Each sea is the sea its name promises (analytic Hs of the 1-D
         * spectrum against the Met Office marine Beaufort table). */
        double u10, hs = ocean_spectrum_hs(&s.params.sea);
        if (strcmp(s.name, "flight") == 0 || strcmp(s.name, "ship-bridge") == 0)
            assert_true(hs > 1.5 && hs <= 4.0);   /* force 6: 3.0 probable, 4.0 max */
        else if (strcmp(s.name, "harbour") == 0)
            assert_true(hs > 0.02 && hs < 0.5);   /* calm */
        else if (strcmp(s.name, "storm") == 0)
            assert_true(hs >= 7.0 && hs <= 12.5); /* force 10: 9.0 probable, 12.5 max */
        if (strcmp(s.name, "flight") == 0) {
            /* whitecaps too: Monahan's coverage at 12 m/s is 1.8 %, seen from the air */
            assert_int_equal(s.effects, OCEAN_FX_HEIGHT | OCEAN_FX_NORMALS | OCEAN_FX_FOAM);
            assert_true(s.params.patch_m > def.patch_m);
            assert_true(s.params.cascades > def.cascades);
            assert_true(cam[1] >= 300.0);
        } else if (strcmp(s.name, "ship-bridge") == 0) {
            assert_int_equal(s.effects, OCEAN_SCENE_FX_ALL);
        } else if (strcmp(s.name, "harbour") == 0) {
            assert_int_equal(s.params.sea.spectrum, OCEAN_SPECTRUM_TMA);
            assert_true(s.params.sea.depth_m >= 3.0 && s.params.sea.depth_m <= 10.0);
            assert_true(s.params.sea.wind_u10 <= 6.0);
            assert_true(s.params.sea.fetch_m >= 1000.0 && s.params.sea.fetch_m <= 10000.0);
            assert_int_equal(s.effects & OCEAN_FX_FOAM, 0);
        } else if (strcmp(s.name, "storm") == 0) {
            assert_int_equal(ocean_beaufort_wind(10, &u10), OCEAN_OK);
            assert_true(s.params.sea.wind_u10 == u10);
            assert_int_equal(s.effects, OCEAN_SCENE_FX_ALL);
            assert_true(s.params.sea.choppiness >= 2.0);
        }
    }
    closedir(d);
    for (int i = 0; i < 4; i++) {
        if (!found[i]) print_error("missing scene %s\n", need[i]);
        assert_true(found[i]);
    }
    assert_true(count >= 4);
}

static void test_scene_layers(void **state)
{
    (void)state;
    ocean_params base;
    ocean_scene s;
    char err[512];
    double u4, u10;
    assert_int_equal(ocean_beaufort_wind(4, &u4), OCEAN_OK);
    assert_int_equal(ocean_beaufort_wind(10, &u10), OCEAN_OK);

    /* The daemon's file gives a Beaufort force; a scene's wind replaces it. */
    const char *daemon = "sea.beaufort = 10\nocean.n = 128\nsea.depth = 50\n";
    assert_int_equal(ocean_conf_load_string("d.conf", daemon, strlen(daemon), &base, err, sizeof err), OCEAN_OK);
    assert_true(base.sea.wind_u10 == u10);
    const char *scene = "scene.name = calm\nscene.effects = height\nsea.wind = 3\n";
    assert_int_equal(ocean_conf_scene_load_string("s.conf", scene, strlen(scene), &base, &s, err, sizeof err),
                     OCEAN_OK);
    assert_true(s.params.sea.wind_u10 == 3.0);
    assert_int_equal(s.params.n, 128);               /* kept from the daemon's file */
    assert_true(s.params.sea.depth_m == 50.0);
    assert_string_equal(s.description, "");          /* scene keys start empty */
    assert_string_equal(s.camera_hint, "");
    assert_int_equal(s.effects, OCEAN_FX_HEIGHT);

    /* ...and the other way round. */
    const char *daemon2 = "sea.wind = 3\n";
    assert_int_equal(ocean_conf_load_string("d.conf", daemon2, strlen(daemon2), &base, err, sizeof err), OCEAN_OK);
    const char *scene2 = "scene.name = rough\nscene.effects = all\nsea.beaufort = 4\n";
    assert_int_equal(ocean_conf_scene_load_string("s.conf", scene2, strlen(scene2), &base, &s, err, sizeof err),
                     OCEAN_OK);
    assert_true(s.params.sea.wind_u10 == u4);
    assert_int_equal(s.effects, OCEAN_SCENE_FX_ALL);

    /* A failed scene load leaves *out alone. */
    ocean_scene before;
    memcpy(&before, &s, sizeof s);
    const char *bad = "scene.name = x\nscene.effects = all\nocean.n = 100\n";
    assert_int_equal(ocean_conf_scene_load_string("s.conf", bad, strlen(bad), &base, &s, err, sizeof err),
                     OCEAN_EINVAL);
    assert_non_null(strstr(err, "s.conf:3: ocean.n: must be a power of two"));
    assert_memory_equal(&s, &before, sizeof s);
    assert_int_equal(ocean_conf_scene_load("config/scenes/none.conf", &base, &s, err, sizeof err), OCEAN_EIO);
    assert_memory_equal(&s, &before, sizeof s);
}

static void test_overrides(void **state)
{
    (void)state;
    ocean_params p, before;
    char err[512];
    double u10;
    ocean_params_default(&p);
    assert_int_equal(ocean_conf_apply("sea.wind=20", &p, err, sizeof err), OCEAN_OK);
    assert_true(p.sea.wind_u10 == 20.0);
    assert_int_equal(ocean_conf_apply("  sea.spectrum = tma  # shallow", &p, err, sizeof err), OCEAN_OK);
    assert_int_equal(p.sea.spectrum, OCEAN_SPECTRUM_TMA);
    assert_int_equal(ocean_conf_apply("sea.beaufort=10", &p, err, sizeof err), OCEAN_OK);
    assert_int_equal(ocean_beaufort_wind(10, &u10), OCEAN_OK);
    assert_true(p.sea.wind_u10 == u10);
    assert_int_equal(ocean_conf_apply("sea.wind=1", &p, err, sizeof err), OCEAN_OK); /* later wins */
    assert_true(p.sea.wind_u10 == 1.0);
    assert_int_equal(ocean_conf_apply("ocean.seed=0xffffffffffffffff", &p, err, sizeof err), OCEAN_OK);
    assert_true(p.seed == UINT64_MAX);

    memcpy(&before, &p, sizeof p);
    static const struct { const char *kv; const char *want; } bad[] = {
        {"sea.wind=101", "--set: sea.wind: out of range [0, 100] m/s: '101'"},
        {"sea.wind", "--set: missing '=' (expected key = value): 'sea.wind'"},
        {"", "--set: expected key=value: ''"},
        {"# only a comment", "--set: expected key=value"},
        {"sea.wnd=3", "--set: unknown key (did you mean 'sea.wind'?): 'sea.wnd'"},
        {"server.port=1", "--set: unknown key"},
        {"ocean.n=100", "--set: ocean.n: must be a power of two"},
        {"sea.wind=nan", "--set: sea.wind: NaN and infinity are not allowed: 'nan'"},
        {"sea.wind=5\n", "--set: control character 0x0A"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        ocean_result r = ocean_conf_apply(bad[i].kv, &p, err, sizeof err);
        if (r == OCEAN_OK || !strstr(err, bad[i].want))
            print_error("case %zu: got '%s', want '%s'\n", i, err, bad[i].want);
        assert_int_not_equal(r, OCEAN_OK);
        assert_non_null(strstr(err, bad[i].want));
        assert_memory_equal(&p, &before, sizeof p);
    }

    /* The generic override on several tables at once. */
    fuzz_kit k;
    ocean_params q;
    const conf_table *t[] = {ocean_conf_table(), &fuzz_kit_table};
    void *g[] = {&q, &k};
    conf_set set = {t, g, 2};
    assert_int_equal(conf_defaults(&set, err, sizeof err), OCEAN_OK);
    assert_int_equal(conf_apply("kit.str=\"x # y\"", &set, err, sizeof err), OCEAN_OK);
    assert_string_equal(k.s, "x # y");
    assert_int_equal(conf_apply("ocean.cascades=3", &set, err, sizeof err), OCEAN_OK);
    assert_int_equal(q.cascades, 3);
    assert_null(conf_find(&set, "kit.nothing", NULL));
    size_t which = 9;
    const conf_entry *e = conf_find(&set, "kit.flags", &which);
    assert_non_null(e);
    assert_int_equal(which, 1);
    assert_int_equal(e->type, CONF_FLAGS);
}

/* ---- output ------------------------------------------------------------------------- */

static char *dump_set(const conf_set *set, unsigned flags, size_t *len)
{
    char *buf = NULL;
    FILE *f = open_memstream(&buf, len);
    assert_non_null(f);
    assert_int_equal(conf_dump(f, set, flags), OCEAN_OK);
    assert_int_equal(fclose(f), 0);
    return buf;
}

static void test_dump(void **state)
{
    (void)state;
    char err[512];
    ocean_params p, q, def;
    ocean_params_default(&def);
    /* Awkward values survive a dump and reload bit for bit. */
    const char *text = "sea.wind = 0.1\nsea.direction = -0\nsea.fetch = 12345.678901234567\n"
                       "sea.phillips_a = 3e-300\nocean.seed = 18446744073709551615\n"
                       "ocean.k_max = 1e-6\nocean.plan = measure\nsea.spectrum = pm\n";
    assert_int_equal(ocean_conf_load_string("in", text, strlen(text), &p, err, sizeof err), OCEAN_OK);
    const conf_table *t[] = {ocean_conf_table()};
    void *g[] = {&p};
    conf_set set = {t, g, 1};
    size_t len;
    char *out = dump_set(&set, CONF_DUMP_HELP, &len);
    assert_int_equal(ocean_conf_load_string("dump", out, len, &q, err, sizeof err), OCEAN_OK);
    assert_memory_equal(&p, &q, sizeof p);
    assert_true(signbit(q.sea.wind_dir_deg));
    assert_non_null(strstr(out, "\nsea.wind = 0.1\n"));
    assert_non_null(strstr(out, "\nsea.spectrum = pierson-moskowitz\n")); /* canonical name */
    assert_non_null(strstr(out, "\n# sea.beaufort =\n"));
    assert_non_null(strstr(out, "# Unit: m/s. Range: [0, 100]. Default: 10.\n"));
    assert_non_null(strstr(out, "# One of: estimate, measure, wisdom. Default: estimate.\n"));
    for (char *l = out; *l; l = strchr(l, '\n') + 1) { /* comments wrap */
        char *nl = strchr(l, '\n');
        assert_non_null(nl);
        assert_true(nl - l <= 80);
    }
    free(out);

    /* Without help: only keys, still loadable; defaults dump to defaults. */
    memcpy(&p, &def, sizeof p);
    out = dump_set(&set, 0, &len);
    assert_null(strstr(out, "Unit:"));
    memset(&q, 0, sizeof q);
    assert_int_equal(ocean_conf_load_string("dump", out, len, &q, err, sizeof err), OCEAN_OK);
    assert_memory_equal(&q, &def, sizeof q);
    free(out);

    /* Strings are quoted when they must be. */
    fuzz_kit k;
    char buf[64];
    const conf_entry *se = &fuzz_kit_entries[5];
    assert_string_equal(se->name, "kit.str");
    static const struct { const char *in, *out; } strs[] = {
        {"plain", "plain"}, {"", "\"\""}, {" lead", "\" lead\""}, {"tail\t", "\"tail\t\""},
        {"a#b", "\"a#b\""}, {"\"q", "\"\\\"q\""}, {"b\\s", "b\\s"}, {"a\"b", "a\"b"}};
    for (size_t i = 0; i < sizeof strs / sizeof strs[0]; i++) {
        memset(&k, 0, sizeof k);
        strcpy(k.s, strs[i].in);
        int n = conf_format(se, &k, buf, sizeof buf);
        assert_string_equal(buf, strs[i].out);
        assert_int_equal(n, (int)strlen(strs[i].out));
        char line[96];
        snprintf(line, sizeof line, "kit.str = %s\n", buf);
        fuzz_kit r;
        assert_int_equal(load_kit(line, &r, err, sizeof err), OCEAN_OK);
        assert_string_equal(r.s, strs[i].in);
    }
    /* conf_format reports the length it needs, like snprintf. */
    strcpy(k.s, "a#b");
    assert_int_equal(conf_format(se, &k, buf, 3), 5);
    assert_string_equal(buf, "\"a");
    k.f = 1 | 64;
    assert_int_equal(conf_format(&fuzz_kit_entries[7], &k, buf, sizeof buf), 3);
    assert_string_equal(buf, "a,d");
    k.f = 0;
    conf_format(&fuzz_kit_entries[7], &k, buf, sizeof buf);
    assert_string_equal(buf, "none");
}

static void test_camera_hint(void **state)
{
    (void)state;
    double v[5];
    assert_int_equal(ocean_conf_camera_hint_parse("1,2,3", v), OCEAN_OK);
    assert_true(v[0] == 1 && v[1] == 2 && v[2] == 3 && v[3] == 0 && v[4] == 0);
    assert_int_equal(ocean_conf_camera_hint_parse(" -1.5 , 2e3,3,90, -10 ", v), OCEAN_OK);
    assert_true(v[0] == -1.5 && v[1] == 2000 && v[3] == 90 && v[4] == -10);
    static const char *const bad[] = {"", "1,2", "1,2,3,4,5,6", "1,,3", "1,2,3,", "a,b,c",
                                      "1,2,nan", "1,2,inf", "1,2,1e999", "1 2 3", "1,2,3x"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_int_equal(ocean_conf_camera_hint_parse(bad[i], v), OCEAN_EINVAL);
}

/* ---- the fuzz seed corpus ------------------------------------------------------------- */

static void test_corpus(void **state)
{
    (void)state;
    size_t elen;
    char *expect = read_all(CORPUS "/EXPECT", &elen);
    assert_non_null(expect);
    DIR *d = opendir(CORPUS);
    assert_non_null(d);
    struct dirent *de;
    int ok = 0, bad = 0;
    while ((de = readdir(d)) != NULL) {
        const char *f = de->d_name;
        if (f[0] == '.') continue;
        char path[512];
        snprintf(path, sizeof path, CORPUS "/%s", f);
        size_t len;
        char *data = read_all(path, &len);
        assert_non_null(data);
        fuzz_conf_outcome out;
        const char *why = fuzz_conf_run((const uint8_t *)data, len, &out);
        free(data);
        if (why) print_error("%s: %s\n", f, why);
        assert_null(why);
        if (strncmp(f, "ok-ocean-", 9) == 0) {
            if (!out.ocean_ok) print_error("%s: %s\n", f, out.ocean_err);
            assert_true(out.ocean_ok);
            ok++;
        } else if (strncmp(f, "ok-scene-", 9) == 0) {
            if (!out.scene_ok) print_error("%s: %s\n", f, out.scene_err);
            assert_true(out.scene_ok);
            ok++;
        } else if (strncmp(f, "ok-kit-", 7) == 0) {
            if (!out.kit_ok) print_error("%s: %s\n", f, out.kit_err);
            assert_true(out.kit_ok);
            ok++;
        } else if (strncmp(f, "bad-", 4) == 0) {
            /* EXPECT holds "file<TAB>N: text"; check the named loader's message. */
            char key[300];
            snprintf(key, sizeof key, "\n%s\t", f);
            char *line = strstr(expect, key);
            if (!line) print_error("%s has no line in EXPECT\n", f);
            assert_non_null(line);
            line += strlen(key);
            char *eol = strchr(line, '\n');
            assert_non_null(eol);
            char want[512];
            snprintf(want, sizeof want, "%.*s", (int)(eol - line), line);
            char *colon = strchr(want, ':');
            assert_non_null(colon);
            *colon = '\0';
            int lineno = atoi(want);
            const char *err, *name;
            int failed;
            if (strncmp(f, "bad-ocean-", 10) == 0) err = out.ocean_err, name = "in.conf", failed = !out.ocean_ok;
            else if (strncmp(f, "bad-scene-", 10) == 0) err = out.scene_err, name = "scene.conf", failed = !out.scene_ok;
            else err = out.kit_err, name = "kit.conf", failed = !out.kit_ok;
            char full[700];
            if (lineno > 0) snprintf(full, sizeof full, "%s:%d:%s", name, lineno, colon + 1);
            else snprintf(full, sizeof full, "%s:%s", name, colon + 1);
            if (!failed || !strstr(err, full)) print_error("%s: got '%s', want '%s'\n", f, err, full);
            assert_true(failed);
            assert_non_null(strstr(err, full));
            bad++;
        }
    }
    closedir(d);
    free(expect);
    assert_true(ok >= 5);
    assert_true(bad >= 20);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tables_check),
        cmocka_unit_test(test_defaults_match_ocean_params_default),
        cmocka_unit_test(test_types_parse),
        cmocka_unit_test(test_bool_spellings),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_long_line_and_file),
        cmocka_unit_test(test_ocean_errors),
        cmocka_unit_test(test_shipped_config),
        cmocka_unit_test(test_shipped_scenes),
        cmocka_unit_test(test_scene_layers),
        cmocka_unit_test(test_overrides),
        cmocka_unit_test(test_dump),
        cmocka_unit_test(test_camera_hint),
        cmocka_unit_test(test_corpus),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
