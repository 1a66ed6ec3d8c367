/*
 * cli.h - shared option handling for the ocean-sim subcommands.
 *
 * Every subcommand accepts the common sea-state options (--spectrum, --wind,
 * ..., --config FILE) plus its own, described by a table of cli_opt.  One
 * parser handles both, so every option is range-checked the same way and a
 * bad one is refused with a message naming it.
 */
#ifndef OCEAN_CLI_H
#define OCEAN_CLI_H

#include <stdio.h>

#include "ocean.h"

typedef enum cli_opt_kind {
    CLI_DOUBLE,   /* double *, checked against [min, max], finite */
    CLI_INT,      /* int *, checked against [min, max] */
    CLI_STRING,   /* const char ** */
    CLI_FLAG,     /* int *, set to 1, takes no argument */
    CLI_U64,      /* uint64_t *, any whole number 0 .. 2^64 - 1 (min, max unused) */
    CLI_CHOICE,   /* int *, index of the value in names[] */
    CLI_EFFECTS   /* unsigned *, OCEAN_FX_* mask from a list of names */
} cli_opt_kind;

/* One option.  Its default is what *target holds before parsing: --help
 * prints that value, so the help text never states a default of its own
 * and cannot disagree with the code.  A default outside [min, max] (or
 * NaN, or NULL) means "not given" and is not shown. */
typedef struct cli_opt {
    const char *name;   /* without the leading "--" */
    cli_opt_kind kind;
    void *target;
    double min, max;
    const char *help;   /* one line; "ARG   text" style */
    const char *const *names;   /* CLI_CHOICE: NULL-terminated value names */
} cli_opt;

/* At most this many options per subcommand (its own and the common ones). */
#define CLI_MAX_OPTS 64

/* What every subcommand gets from the common options. */
typedef struct cli_common {
    ocean_params params;
    unsigned effects;      /* --effects, default all four */
    double time;           /* --time T, s */
    int json;              /* --json */
    const char *config;    /* --config FILE (applied before other options) */
} cli_common;

/* Parses argv (argv[0] is the subcommand name).  Common options go to *c
 * (defaults: ocean_params_default, then --config FILE wherever it stands,
 * then the other options), the subcommand's to its table.  Returns 0 on
 * success, 1 if --help or --show-options was printed, 2 on error (message already printed to stderr, naming the
 * option).  c NULL: a command that takes no sea; its own options only.  Positional arguments are refused unless npos != NULL, in which
 * case they are collected into pos[] (at most *npos; *npos gets the count). */
int cli_parse(int argc, char **argv, const char *usage,
              const cli_opt *opts, int nopts, cli_common *c,
              const char **pos, int *npos);

/* Creates an ocean from c->params and a frame for it, printing the reason
 * on failure.  Returns 0, or 1 with nothing left allocated. */
int cli_make_ocean(const cli_common *c, ocean **o, ocean_frame **f);

/* Parses "height,displacement,normals,foam" into an OCEAN_FX_* mask. */
int cli_parse_effects(const char *s, unsigned *out);

/* Monotonic wall clock in milliseconds. */
double cli_now_ms(void);
/* The whole of file path ("-": stdin), NUL-terminated, to free; NULL after
 * printing why (or out of memory). */
char *cli_read_file(const char *path);

/* Median of v[0..n) (sorts v in place); n >= 1. */
double cli_median(double *v, int n);

/* Subcommands: each returns the process exit status. */
int cmd_stats(int argc, char **argv);
int cmd_bake(int argc, char **argv);
int cmd_sample(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_query(int argc, char **argv);
int cmd_filter(int argc, char **argv);
int cmd_wake(int argc, char **argv);
int cmd_render(int argc, char **argv);
int cmd_mesh(int argc, char **argv);
int cmd_wisdom(int argc, char **argv);

/* Prints a cJSON object (pretty, one trailing newline) to stdout and frees
 * it; prints nothing if cJSON cannot allocate the text. */
struct cJSON;
void cli_print_json(struct cJSON *o);

#endif
