# oceand - top-level build.
#
#   make          build everything into build/
#   make test     install missing Debian packages, build, run every test
#                 (plain build, then again under ASan + UBSan)
#   make run      install what building and running need (Debian packages
#                 only, no npm), build, start oceand on config/oceand.conf;
#                 ARGS="--port 0 --scene storm" passes options to oceand
#   make bench    run the benchmarks, write tests/bench/REPORT.md
#   make fuzz     run each libFuzzer target for FUZZ_SECONDS
#   make install  PREFIX=/usr/local (DESTDIR for staging): programs, the
#                 client library (static and shared, pkg-config oceanclient),
#                 the simulator library (pkg-config oceansim), headers,
#                 config, scenes, the web viewer, a systemd unit
#   make clean
#
# Builds run in parallel (one job per core) unless the command line gives -j,
# and keep their objects, so a second `make` has nothing to do.
#
# Sources are found by directory, so a new module is a new .c file:
#   sim/*.c -> libocean_sim.a        protocol/*.c -> libocean_proto.a
#   clients/c/*.c -> libocean_client.a    server/*.c -> oceand
#   sim/cli/*.c -> ocean-sim        clients/c/cli/*.c -> ocean-client
#   tests/test_*.c -> one test program each    tests/bench/*.c -> bench programs

BUILD ?= build
CC ?= gcc
SAN ?= 0
OPT ?= -O2
PREFIX ?= /usr/local
# Where `make install` puts oceand's data and config; the installed oceand is
# compiled with these as its defaults (build/oceand keeps the source tree's).
DATADIR ?= $(PREFIX)/share/oceand
SYSCONFDIR ?= $(PREFIX)/etc/oceand
UNITDIR ?= $(PREFIX)/lib/systemd/system
ARGS ?=

# One job per core unless the command line chose (-j N, or -j1 for serial).
ifeq ($(filter -j%,$(MAKEFLAGS)),)
MAKEFLAGS += -j$(shell nproc 2>/dev/null || echo 2)
endif
# Objects of pattern-built programs would otherwise be intermediate files:
# deleted after the link, so the next `make` rebuilt and relinked everything.
.SECONDARY:

CPPFLAGS += -D_GNU_SOURCE -I/usr/include/OpenEXR -I/usr/include/cjson
# Layering by the build: each layer sees its own headers and the layers'
# below it (sim <- protocol <- clients/c; sim <- protocol <- server), so an
# include that points up does not compile (tests/test_build.sh proves it).
# Test programs and benches see every layer.
INC = -Isim -Iprotocol -Iclients/c -Iserver
$(BUILD)/obj/sim/%.o $(BUILD)/pic/sim/%.o: INC = -Isim
$(BUILD)/obj/protocol/%.o $(BUILD)/pic/protocol/%.o: INC = -Isim -Iprotocol
$(BUILD)/obj/clients/%.o $(BUILD)/pic/clients/%.o: INC = -Isim -Iprotocol -Iclients/c
$(BUILD)/obj/server/%.o: INC = -Isim -Iprotocol -Iserver
# The installed API: `make install` puts it in PREFIX/include/oceand/ and a
# program includes <oceand/oceanclient.h> (so no generic name - conf.h,
# codec.h - sits at the top of anyone's include path).  The examples are
# built as a user builds them, against BUILD/include/oceand, a staged copy.
PUBLIC_HEADERS := $(filter-out sim/ocean_internal.h sim/mesh_internal.h sim/ocean_reference.h,$(wildcard sim/*.h)) \
                  $(wildcard protocol/*.h) $(wildcard clients/c/*.h)
$(BUILD)/obj/clients/examples/%.o: INC = -I$(BUILD)/include
CFLAGS += -std=c11 $(OPT) -g -Wall -Wextra -Werror -fopenmp -pthread
# What the client library (protocol + clients/c + the sim/ files they use)
# links against, OpenEXRCore for protocol/'s exr codec; then what the
# simulator adds.  The .pc files' Libs.private are generated from these, so
# they cannot disagree.
LIB_LDLIBS := -lwebsockets -lOpenEXRCore-3_1 -lzstd -lcjson -lm -lpthread
SIM_LDLIBS := -lfftw3f_omp -lfftw3f -lproj -lm
LDLIBS += $(LIB_LDLIBS) $(SIM_LDLIBS) -lhiredis
ifeq ($(SAN),1)
CFLAGS += -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
LDFLAGS += -fsanitize=address,undefined
endif

SIM_SRC := $(wildcard sim/*.c)
PROTO_SRC := $(wildcard protocol/*.c)
CLIENT_SRC := $(wildcard clients/c/*.c)
SERVER_SRC := $(wildcard server/*.c)
SIMCLI_SRC := $(wildcard sim/cli/*.c)
CLIENTCLI_SRC := $(wildcard clients/c/cli/*.c)
EXAMPLE_SRC := $(wildcard clients/examples/*.c)
TEST_SRC := $(wildcard tests/test_*.c)
BENCH_SRC := $(wildcard tests/bench/*.c)
TESTLIB_SRC := $(wildcard tests/lib/*.c)

obj = $(patsubst %.c,$(BUILD)/obj/%.o,$(1))

LIB_SIM := $(BUILD)/libocean_sim.a
LIB_PROTO := $(BUILD)/libocean_proto.a
LIB_CLIENT := $(BUILD)/libocean_client.a
LIB_SERVER := $(BUILD)/libocean_server.a
LIB_TEST := $(BUILD)/libocean_testlib.a
# Link order: dependants first.
ALL_LIBS := $(if $(CLIENT_SRC),$(LIB_CLIENT)) $(if $(SERVER_SRC),$(LIB_SERVER)) \
            $(if $(PROTO_SRC),$(LIB_PROTO)) $(LIB_SIM)

# The installable client library, in one archive and one shared object
# (built from -fPIC objects of its own): protocol + clients/c and the
# sim/ files they use (results, time, the config parser, the entity table
# and the wake patterns it reads), no simulator, so
# a program that links it gets no FFTW and no OpenMP.
OC_VERSION := $(shell sed -n 's/^\#define OC_VERSION "\(.*\)"/\1/p' clients/c/oceanclient.h)
OC_SOVERSION := $(firstword $(subst ., ,$(OC_VERSION)))
OCLIB_SIM_SRC := sim/ocean_result.c sim/ocean_time.c sim/conf.c sim/entity.c sim/wake_pattern.c sim/wake_field.c sim/rotor_wash.c
OCLIB_SRC := $(filter-out clients/c/oc_ship_offline.c,$(CLIENT_SRC)) $(PROTO_SRC) $(OCLIB_SIM_SRC)
OCLIB_A := $(BUILD)/liboceanclient.a
OCLIB_SO := $(BUILD)/liboceanclient.so.$(OC_VERSION)
# The installable simulator, for programs that run an ocean of their own
# (the ship example's --offline): the rest of sim/, less the direct-sum
# reference of the tests and benchmarks, and the client piece that runs on
# it.  It takes the shared sim/ files from liboceanclient (oceansim.pc
# requires oceanclient), so no symbol is in both.
OCSIM_SRC := $(filter-out $(OCLIB_SIM_SRC) sim/ocean_reference.c,$(SIM_SRC)) clients/c/oc_ship_offline.c
OCSIM_A := $(BUILD)/liboceansim.a
OCSIM_SO := $(BUILD)/liboceansim.so.$(OC_VERSION)
pic = $(patsubst %.c,$(BUILD)/pic/%.o,$(1))

PROGS := $(BUILD)/ocean-sim \
         $(if $(SERVER_SRC),$(BUILD)/oceand) \
         $(if $(CLIENTCLI_SRC),$(BUILD)/ocean-client) \
         $(patsubst clients/examples/%.c,$(BUILD)/examples/%,$(EXAMPLE_SRC))
TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))
BENCHES := $(patsubst tests/bench/%.c,$(BUILD)/bench/%,$(BENCH_SRC))
WASM_CC ?= clang
WASM := clients/web/ocean.wasm
WASM_SRC := clients/wasm/oc_wasm.c protocol/codec.c protocol/proto.c protocol/proto_buf.c sim/ocean_result.c \
    sim/ocean_time.c clients/c/oc_held.c clients/c/oc_wakes.c sim/entity.c sim/wake_pattern.c sim/wake_field.c sim/rotor_wash.c

.PHONY: all deps test test-plain test-asan test-bins run bench fuzz clean install
.DEFAULT_GOAL := all

all: $(PROGS) $(TESTS) $(BENCHES) $(OCLIB_A) $(OCLIB_SO) $(OCSIM_A) $(OCSIM_SO) $(WASM)

deps:
	@bash .ci/deps.sh run

# The ocean's vector passes need -O3's vectoriser (GCC 12's -O2 cost model
# leaves them scalar): the spectrum stage's row passes, the evaluation's
# Jacobian and foam pass, the per-vertex sampling and the accurate reading.
# A command-line OPT (the ASan build) still wins.
SIM_VEC_SRC := sim/ocean.c sim/ocean_stage.c sim/ocean_sample.c sim/ocean_accurate.c
$(call obj,$(SIM_VEC_SRC)) $(call pic,$(SIM_VEC_SRC)): OPT = -O3
# sqrt must not set errno there, or GCC cannot vectorise ocean_deep_turns;
# and a comparison must not be taken to trap (nothing here enables FP
# traps), or GCC cannot turn the foam trails' selects into blends.
$(call obj,$(SIM_VEC_SRC)) $(call pic,$(SIM_VEC_SRC)): CFLAGS += -fno-math-errno -fno-trapping-math

# The browser viewer's decoders: protocol/'s own (messages and codecs) and
# the C library's store of samples in time (oc_held.c), compiled to
# WebAssembly with Debian's clang, wasm-ld (lld) and wasi-libc, and written
# beside the page (the daemon serves clients/web/).  Exports and the zstd
# bridge: clients/wasm/oc_wasm.c; loader: clients/web/codec.js.
$(WASM): $(WASM_SRC) $(wildcard protocol/*.h) sim/ocean_result.h sim/ocean_time.h clients/c/oc_held.h \
    clients/c/oc_wakes.h sim/entity.h sim/wake_pattern.h sim/wake_field.h sim/wake_internal.h sim/rotor_wash.h
	$(WASM_CC) --target=wasm32-wasi --sysroot=/usr -std=c11 -O2 -Wall -Wextra -Werror -D_GNU_SOURCE \
	    -Isim -Iprotocol -Iclients/c -ffunction-sections -fdata-sections -nostartfiles \
	    -Wl,--no-entry -Wl,--gc-sections -Wl,--strip-all $(WASM_SRC) -o $@

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(INC) $(CFLAGS) -MMD -MP -c $< -o $@

$(BUILD)/pic/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(INC) $(CFLAGS) -fPIC -MMD -MP -c $< -o $@

$(OCLIB_A): $(call obj,$(OCLIB_SRC))
	rm -f $@ && ar rcs $@ $^
# -z defs: every symbol the library uses is resolved by what it names (the
# sanitizer runtime is only there in the executable, so not under SAN).
# Linked without -fopenmp: nothing in it runs an OpenMP team.
$(OCLIB_SO): $(call pic,$(OCLIB_SRC))
	$(CC) -shared -Wl,-soname,liboceanclient.so.$(OC_SOVERSION) $(if $(filter 1,$(SAN)),,-Wl,-z,defs) \
	    $(filter-out -fopenmp,$(CFLAGS)) $(LDFLAGS) $^ $(LIB_LDLIBS) -o $@
	ln -sf $(notdir $@) $(BUILD)/liboceanclient.so.$(OC_SOVERSION)
	ln -sf $(notdir $@) $(BUILD)/liboceanclient.so
$(OCSIM_A): $(call obj,$(OCSIM_SRC))
	rm -f $@ && ar rcs $@ $^
$(OCSIM_SO): $(call pic,$(OCSIM_SRC)) $(OCLIB_SO)
	$(CC) -shared -Wl,-soname,liboceansim.so.$(OC_SOVERSION) $(if $(filter 1,$(SAN)),,-Wl,-z,defs) \
	    $(CFLAGS) $(LDFLAGS) $^ $(SIM_LDLIBS) -o $@
	ln -sf $(notdir $@) $(BUILD)/liboceansim.so.$(OC_SOVERSION)
	ln -sf $(notdir $@) $(BUILD)/liboceansim.so

$(LIB_SIM): $(call obj,$(SIM_SRC))
$(LIB_PROTO): $(call obj,$(PROTO_SRC))
$(LIB_CLIENT): $(call obj,$(CLIENT_SRC))
# The daemon's modules (all but main.c) form a library so tests can drive them.
$(LIB_SERVER): $(call obj,$(filter-out server/main.c,$(SERVER_SRC)))
$(LIB_TEST): $(call obj,$(TESTLIB_SRC))
$(BUILD)/%.a:
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

# ocean-sim render writes PNG with libpng.
$(BUILD)/ocean-sim: $(call obj,$(SIMCLI_SRC)) $(ALL_LIBS)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -lpng -o $@
$(BUILD)/oceand: $(call obj,server/main.c) $(ALL_LIBS)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -o $@
# ocean-client's load generator frames WebSocket with libwslay (load_direct.c).
$(BUILD)/ocean-client: $(call obj,$(CLIENTCLI_SRC)) $(ALL_LIBS)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -lwslay -o $@
$(BUILD)/include/oceand: $(PUBLIC_HEADERS)
	rm -rf $@ && mkdir -p $@ && ln -s $(abspath $(PUBLIC_HEADERS)) $@/ && touch $@
$(call obj,$(EXAMPLE_SRC)): | $(BUILD)/include/oceand
$(BUILD)/examples/%: $(BUILD)/obj/clients/examples/%.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -o $@
$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(if $(TESTLIB_SRC),$(LIB_TEST)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -lcmocka -o $@
# test_render drives ocean-sim render's own modules.
RENDER_SRC := sim/cli/render.c sim/cli/render_shade.c sim/cli/cli.c
$(BUILD)/obj/tests/test_render.o: INC += -Isim/cli
$(BUILD)/tests/test_render: $(BUILD)/obj/tests/test_render.o $(call obj,$(RENDER_SRC)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -lcmocka -o $@
$(BUILD)/bench/%: $(BUILD)/obj/tests/bench/%.o $(if $(TESTLIB_SRC),$(LIB_TEST)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -o $@

# deps first, then one pass after the other: each pass builds in parallel,
# the two passes must not run side by side.  The sanitizer pass's build runs
# beside the plain pass's tests at nice 19: it takes the CPU their waits for
# real-time streams leave, and yields it to them.
test:
	@bash .ci/deps.sh test
	@echo "== plain build ($$(date +%T))"
	@$(MAKE) --no-print-directory all
	@echo "== plain pass, the sanitizer build beside it ($$(date +%T))"
	@mkdir -p build/asan
	@(nice -n 19 $(MAKE) --no-print-directory BUILD=build/asan SAN=1 OPT=-O1 test-bins \
	  >build/asan/build.log 2>&1 || tail -30 build/asan/build.log) & \
	 $(MAKE) --no-print-directory test-plain; rc=$$?; wait; exit $$rc
	@echo "== sanitizer pass ($$(date +%T))"
	@$(MAKE) --no-print-directory test-asan
	@cat $(BUILD)/test-summary build/asan/test-summary | \
	 awk '{p += $$1; f += $$2; s += $$3} END {printf "%d passed, %d failed, %d skipped\n", p, f, s; exit (f > 0)}'

test-plain: all
	@bash tests/run.sh $(BUILD) plain

# The sanitizer pass builds what it runs: the test programs and the daemon
# three of them start (not the client library's PIC copy, the benches, the
# examples or the command-line tools, which the plain pass builds and tests).
test-bins: $(TESTS) $(if $(SERVER_SRC),$(BUILD)/oceand)

test-asan:
	@$(MAKE) --no-print-directory BUILD=build/asan SAN=1 OPT=-O1 test-bins
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	 OCEAN_TEST_SANITIZED=1 bash tests/run.sh build/asan asan

run: deps
	@$(MAKE) --no-print-directory all
	./$(BUILD)/oceand --config config/oceand.conf $(ARGS)

bench:
	@bash .ci/deps.sh bench
	@$(MAKE) --no-print-directory all
	@bash tests/bench/run.sh $(BUILD)

FUZZ_SECONDS ?= 60
fuzz:
	@bash .ci/deps.sh run
	@bash tests/fuzz/run.sh $(FUZZ_SECONDS)

# The installed oceand is build/oceand relinked with main.c compiled for the
# prefix: with no --config it serves DATADIR/web and DATADIR/scenes.
INST_DEFS = -DOCEAND_DATADIR='"$(DATADIR)"' -DOCEAND_SYSCONFDIR='"$(SYSCONFDIR)"'
install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/oceand \
	    $(DESTDIR)$(DATADIR)/web $(DESTDIR)$(DATADIR)/scenes $(DESTDIR)$(SYSCONFDIR) $(DESTDIR)$(UNITDIR) \
	    $(BUILD)/install
	install -m 755 $(filter-out $(BUILD)/oceand $(BUILD)/examples/%,$(PROGS)) $(DESTDIR)$(PREFIX)/bin/
	$(CC) $(CPPFLAGS) -Isim -Iprotocol -Iserver $(INST_DEFS) $(CFLAGS) -c server/main.c -o $(BUILD)/install/main.o
	$(CC) $(CFLAGS) $(LDFLAGS) $(BUILD)/install/main.o $(ALL_LIBS) $(LDLIBS) -o $(BUILD)/install/oceand
	install -m 755 $(BUILD)/install/oceand $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(OCLIB_A) $(OCLIB_SO) $(OCSIM_A) $(OCSIM_SO) $(DESTDIR)$(PREFIX)/lib/
	ln -sf $(notdir $(OCLIB_SO)) $(DESTDIR)$(PREFIX)/lib/liboceanclient.so.$(OC_SOVERSION)
	ln -sf $(notdir $(OCLIB_SO)) $(DESTDIR)$(PREFIX)/lib/liboceanclient.so
	ln -sf $(notdir $(OCSIM_SO)) $(DESTDIR)$(PREFIX)/lib/liboceansim.so.$(OC_SOVERSION)
	ln -sf $(notdir $(OCSIM_SO)) $(DESTDIR)$(PREFIX)/lib/liboceansim.so
	install -m 644 $(PUBLIC_HEADERS) $(DESTDIR)$(PREFIX)/include/oceand/
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@VERSION@|$(OC_VERSION)|g' \
	    -e 's|@LIBS_PRIVATE@|$(LIB_LDLIBS)|g' \
	    clients/c/oceanclient.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/oceanclient.pc
	sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@VERSION@|$(OC_VERSION)|g' \
	    -e 's|@LIBS_PRIVATE@|$(SIM_LDLIBS) -fopenmp|g' \
	    sim/oceansim.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/oceansim.pc
	cp -R clients/web/. $(DESTDIR)$(DATADIR)/web/
	install -m 644 config/scenes/*.conf $(DESTDIR)$(DATADIR)/scenes/
	sed -e 's|^server.web_root = .*|server.web_root = $(DATADIR)/web|' \
	    -e 's|^server.scene_dir = .*|server.scene_dir = $(DATADIR)/scenes|' \
	    config/oceand.conf > $(BUILD)/install/oceand.conf
	install -m 644 $(BUILD)/install/oceand.conf $(DESTDIR)$(SYSCONFDIR)/oceand.conf
	sed -e 's|@BINDIR@|$(PREFIX)/bin|g' -e 's|@SYSCONFDIR@|$(SYSCONFDIR)|g' \
	    server/oceand.service.in > $(DESTDIR)$(UNITDIR)/oceand.service

clean:
	rm -rf build $(WASM)

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
