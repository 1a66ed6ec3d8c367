# oceand - top-level build.
#
#   make          build everything into build/
#   make test     install missing Debian packages, build, run every test
#                 (plain build, then again under ASan + UBSan)
#   make run      install, build, start oceand on config/oceand.conf
#   make bench    run the benchmarks, write tests/bench/REPORT.md
#   make fuzz     run each libFuzzer target for FUZZ_SECONDS
#   make clean
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

CPPFLAGS += -D_GNU_SOURCE -Isim -Iprotocol -Iclients/c -Iserver \
            -I/usr/include/OpenEXR -I/usr/include/cjson
CFLAGS += -std=c11 $(OPT) -g -Wall -Wextra -Werror -fopenmp -pthread
LDLIBS += -lwebsockets -lOpenEXRCore-3_1 -lfftw3f_omp -lfftw3f \
          -lzstd -lcjson -lm -lpthread
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

PROGS := $(BUILD)/ocean-sim \
         $(if $(SERVER_SRC),$(BUILD)/oceand) \
         $(if $(CLIENTCLI_SRC),$(BUILD)/ocean-client) \
         $(patsubst clients/examples/%.c,$(BUILD)/examples/%,$(EXAMPLE_SRC))
TESTS := $(patsubst tests/%.c,$(BUILD)/tests/%,$(TEST_SRC))
BENCHES := $(patsubst tests/bench/%.c,$(BUILD)/bench/%,$(BENCH_SRC))

.PHONY: all deps test test-plain test-asan run bench fuzz clean install
.DEFAULT_GOAL := all

all: $(PROGS) $(TESTS) $(BENCHES)

deps:
	@bash .ci/deps.sh

# The spectrum stage's row passes need -O3's vectoriser (GCC 12's -O2 cost
# model leaves them scalar); a command-line OPT (the ASan build) still wins.
$(BUILD)/obj/sim/ocean.o: OPT = -O3

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -MMD -MP -c $< -o $@

$(LIB_SIM): $(call obj,$(SIM_SRC))
$(LIB_PROTO): $(call obj,$(PROTO_SRC))
$(LIB_CLIENT): $(call obj,$(CLIENT_SRC))
# The daemon's modules (all but main.c) form a library so tests can drive them.
$(LIB_SERVER): $(call obj,$(filter-out server/main.c,$(SERVER_SRC)))
$(LIB_TEST): $(call obj,$(TESTLIB_SRC))
$(BUILD)/%.a:
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(BUILD)/ocean-sim: $(call obj,$(SIMCLI_SRC)) $(ALL_LIBS)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -o $@
$(BUILD)/oceand: $(call obj,server/main.c) $(ALL_LIBS)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -o $@
# ocean-client's load generator frames WebSocket with libwslay (load_direct.c).
$(BUILD)/ocean-client: $(call obj,$(CLIENTCLI_SRC)) $(ALL_LIBS)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -lwslay -o $@
$(BUILD)/examples/%: $(BUILD)/obj/clients/examples/%.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -o $@
$(BUILD)/tests/%: $(BUILD)/obj/tests/%.o $(if $(TESTLIB_SRC),$(LIB_TEST)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -lcmocka -o $@
$(BUILD)/bench/%: $(BUILD)/obj/tests/bench/%.o $(if $(TESTLIB_SRC),$(LIB_TEST)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $(LDFLAGS) $^ $(LDLIBS) -o $@

test: deps
	@$(MAKE) --no-print-directory test-plain test-asan
	@cat $(BUILD)/test-summary build/asan/test-summary | \
	 awk '{p += $$1; f += $$2} END {printf "%d passed, %d failed\n", p, f; exit (f > 0)}'

test-plain: all
	@bash tests/run.sh $(BUILD) plain

test-asan:
	@$(MAKE) --no-print-directory BUILD=build/asan SAN=1 OPT=-O1 all
	@ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
	 OCEAN_TEST_SANITIZED=1 bash tests/run.sh build/asan asan

run: deps all
	./$(BUILD)/oceand --config config/oceand.conf

bench: deps all
	@bash tests/bench/run.sh $(BUILD)

FUZZ_SECONDS ?= 60
fuzz: deps
	@bash tests/fuzz/run.sh $(FUZZ_SECONDS)

install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/oceand
	install -m 755 $(PROGS) $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(ALL_LIBS) $(DESTDIR)$(PREFIX)/lib/
	install -m 644 sim/*.h protocol/*.h clients/c/*.h $(DESTDIR)$(PREFIX)/include/oceand/
	sed 's|@PREFIX@|$(PREFIX)|g' clients/c/oceanclient.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/oceanclient.pc

clean:
	rm -rf build

-include $(shell find $(BUILD)/obj -name '*.d' 2>/dev/null)
