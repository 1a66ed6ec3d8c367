/*
 * conf.h - the project's one configuration parser: `key = value` text checked
 * against tables of typed, range-limited, documented entries.
 *
 * A module describes its settings once, in a conf_table (name, type, range,
 * default, place in its struct, help).  The same table drives loading
 * (defaults, then a file, then --set overrides), the error messages, and
 * conf_dump, which prints the effective configuration as a commented file.
 * Several tables load from one file at once (the simulation's sea.* and
 * ocean.* keys beside the daemon's server.* keys), each into its own target.
 *
 * File syntax (UTF-8, at most CONF_MAX_LINE bytes a line, CONF_MAX_FILE
 * bytes in all, LF or CRLF line ends, an optional UTF-8 byte-order mark):
 *
 *     # a whole-line comment
 *     sea.wind = 12.5          # a trailing comment
 *     scene.description = "quoted: may hold # and \" and \\"
 *
 * Keys are dotted lower-case names ([a-z0-9_-] segments joined by '.').
 * A value runs to '#' or the line's end, blanks trimmed; a double-quoted
 * value may hold '#' and the escapes \" and \\.  Each key may appear once
 * per source.  Every failure leaves the targets untouched and writes
 *
 *     file:line: message: 'offending text'
 *
 * into the caller's buffer (the text shown with control and non-UTF-8 bytes
 * escaped, long text cut).  Loads are all-or-nothing: values are applied to
 * scratch copies and committed only when the whole source is good, so a bad
 * SIGHUP reload or admin change leaves the running configuration as it was.
 *
 * Numbers are read and written with strtod/snprintf, so the process must
 * keep the C numeric locale (nothing in oceand calls setlocale).  All
 * functions are reentrant: tables are read-only, state lives on the stack
 * and in the caller's targets.
 */
#ifndef OCEAN_CONF_H
#define OCEAN_CONF_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "ocean_result.h"

#define CONF_MAX_LINE 1024         /* bytes per line, line end excluded */
#define CONF_MAX_FILE (1u << 20)   /* bytes per source */
#define CONF_MAX_KEY 64            /* bytes per key */

typedef enum conf_type {
    CONF_INT,     /* int; decimal; [min, max] */
    CONF_U64,     /* uint64_t; decimal or 0x hex; [min, max], max >= 2^64 is no bound */
    CONF_DOUBLE,  /* double; decimal (e.g. 1e5); finite unless CONF_F_INF_OK; [min, max] */
    CONF_BOOL,    /* int 0/1; on/off, true/false, yes/no, 1/0 */
    CONF_STRING,  /* char[size]; at most size-1 bytes of UTF-8 */
    CONF_ENUM,    /* int; one name of names[] -> its value */
    CONF_FLAGS    /* unsigned; comma list of names[] -> OR of their values;
                     "none" is 0, "all" is every name; min = 1 refuses 0 */
} conf_type;

/* Entry flags. */
#define CONF_F_REQUIRED 1u  /* a loaded source must give this key */
#define CONF_F_NOSTORE 2u   /* no field: the value only reaches the hook;
                               conf_dump shows the key commented out */
#define CONF_F_INF_OK 4u    /* CONF_DOUBLE: "inf" (+infinity) is allowed */

typedef struct conf_name {
    const char *name;  /* lower case; matched case-insensitively */
    unsigned value;    /* ENUM: the int stored; FLAGS: the bits */
} conf_name;

struct conf_entry;

/* Called after a value has parsed and passed its range, with the scratch
 * target and the typed value (int *, uint64_t *, double *, const char *,
 * unsigned *).  Used for values that check more than a range (a power of
 * two) or that set other fields (a Beaufort force sets the wind).  Returns
 * OCEAN_OK, or an error with a message (without file:line) in msg. */
typedef ocean_result (*conf_hook)(void *target, const struct conf_entry *e,
                                  const void *value, char *msg, size_t msglen);

typedef struct conf_entry {
    const char *name;         /* "sea.wind" */
    conf_type type;
    size_t offset;            /* offsetof(target struct, field) */
    size_t size;              /* CONF_STRING: capacity of the char array */
    double min, max;          /* INT, U64, DOUBLE: inclusive; FLAGS: min 1 = non-empty */
    const char *def;          /* default, as file text; NULL: not applied
                                 (optional keys; STRING defaults to "") */
    const conf_name *names;   /* ENUM, FLAGS: terminated by {NULL, 0} */
    const char *unit;         /* "m/s", or NULL */
    const char *help;         /* one sentence or two, for conf_dump */
    unsigned flags;           /* CONF_F_* */
    int group;                /* > 0: keys sharing a group exclude each
                                 other within one source */
    conf_hook hook;           /* or NULL */
} conf_entry;

typedef struct conf_table {
    const char *name;         /* "ocean", "scene", "server" */
    const char *title;        /* section heading for conf_dump */
    const conf_entry *entries;
    size_t count;
    size_t target_size;       /* sizeof the target struct (for scratch copies) */
} conf_table;

/* A set of tables loaded together, each writing into its own target. */
typedef struct conf_set {
    const conf_table *const *tables;
    void *const *targets;
    size_t n;
} conf_set;

/* Load options.  NULL means: defaults first, no key skipped. */
#define CONF_NO_DEFAULTS 1u  /* overlay on the targets' current values */
typedef struct conf_load_opts {
    unsigned flags;
    /* NULL-terminated namespaces ("server") whose keys another program owns:
     * such lines are syntax-checked but not interpreted.  Lets ocean-sim
     * read the daemon's file. */
    const char *const *ignore;
} conf_load_opts;

/* Checks a table itself: names well formed and unique across the set,
 * every default parses and is in range, min <= max, string sizes > 1.
 * For tests and start-up; message in err. */
ocean_result conf_set_check(const conf_set *set, char *err, size_t errlen);

/* Writes every entry's default (entries without one are left alone, except
 * strings, which become "").  Fails only on a broken table. */
ocean_result conf_defaults(const conf_set *set, char *err, size_t errlen);

/* Loads a file (or a buffer of len bytes named `name` in messages).
 * Applies defaults first unless opts->flags has CONF_NO_DEFAULTS.
 * Returns OCEAN_OK, OCEAN_EIO (cannot read), OCEAN_ETOOBIG (file over
 * CONF_MAX_FILE), OCEAN_EFORMAT (syntax, unknown key, bad value),
 * OCEAN_EINVAL (out of range, hook refused) or OCEAN_ENOMEM; the targets
 * change only on OCEAN_OK. */
ocean_result conf_load_file(const char *path, const conf_set *set,
                            const conf_load_opts *opts, char *err, size_t errlen);
ocean_result conf_load_string(const char *name, const char *text, size_t len,
                              const conf_set *set, const conf_load_opts *opts,
                              char *err, size_t errlen);

/* Applies one "key=value" override on top of the current values (the
 * command line's --set).  Same syntax and checks as a file line; messages
 * read "--set: message: 'text'". */
ocean_result conf_apply(const char *keyvalue, const conf_set *set,
                        char *err, size_t errlen);

/* Finds a key; returns its entry and sets *table (if non-NULL) to the index
 * of its table, or NULL. */
const conf_entry *conf_find(const conf_set *set, const char *key, size_t *table);

/* Formats the entry's current value in target as file text that parses
 * back to the same bits (doubles in shortest round-trip form; strings
 * quoted when they must be).  Returns the length conf would need (like
 * snprintf). */
int conf_format(const conf_entry *e, const void *target, char *buf, size_t len);

/* Prints the effective configuration as a loadable file: a heading per
 * table and, with CONF_DUMP_HELP, each key's help, unit, range, accepted
 * names and default as comments above it.  NOSTORE keys appear commented
 * out.  Output reloads to the same values.  Returns OCEAN_EIO on a write
 * error. */
#define CONF_DUMP_HELP 1u
ocean_result conf_dump(FILE *out, const conf_set *set, unsigned flags);

/* Copies len bytes of text into out (outlen bytes, always terminated) fit
 * to quote in a message printed to a terminal or log: printable ASCII and
 * valid UTF-8 as they are, invisible format characters (byte-order mark,
 * bidi controls) as \uNNNN, control and other bytes as \xNN, cut after
 * CONF_SHOW_MAX bytes with "...".  Every parser of the project quotes
 * offending input through it, so no file or message can write an escape
 * sequence to the reader's terminal. */
#define CONF_SHOW_MAX 80
void conf_show_text(const char *text, size_t len, char *out, size_t outlen);

#endif
