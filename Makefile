# tdc_delaunay: PGXS build of the extension, plus the PostgreSQL-free core,
# its command-line front end ./tdc and the core test suite.
#
#   make && make install        build and install the extension (needs pg_config)
#   make tdc                    ./tdc without PostgreSQL
#   make check-core             core suite (prints "N passed, N failed")
#   make check-core-asan        core suite under AddressSanitizer + UBSan (clang)
#   make check-core-tsan        core suite under ThreadSanitizer (clang)
#   make installcheck           pg_regress against a running server
#   make test                   everything, on a throw-away cluster (scripts/test.sh)
#   make demo                   set-up + side-by-side demo (scripts/demo.sh)
#   make bench                  benchmarks (bench/run.sh)
#   make bench-tin              the TIN benchmark alone (bench/tin_bench.sh, issue 29)
#   make bench-coverage         the coverage benchmark alone (bench/coverage_bench.sh, issue 40)

# Three extensions from one library: tdc_delaunay (needs postgis),
# tdc_delaunay_raster (needs tdc_delaunay and postgis_raster) and
# tdc_delaunay_pointcloud (needs pgpointcloud and tdc_delaunay_raster), so
# that CREATE EXTENSION tdc_delaunay never needs postgis_raster or
# pgpointcloud.  The library reads and writes rasters, and reads pcpatch
# values, in their stored formats without linking PostGIS or pgpointcloud.
EXTENSION = tdc_delaunay tdc_delaunay_raster tdc_delaunay_pointcloud
EXTVERSION = 1.2.0
RASTER_EXTVERSION = 1.2.0
POINTCLOUD_EXTVERSION = 1.2.0
MODULE_big = tdc_delaunay
# The install script of this version is made from one file per feature, in
# this order (the rule is below); older base scripts (0.1.0, 1.0.0 as it was
# built from src/sql before tin.sql, and 1.1.0 as it was built before
# ST_TDCContours took a method and tdc_delaunay_tiled a tile column in one C
# function) and the upgrade scripts ship as they were released, and
# test/release.sh checks that the library still has every C function any of
# them names.
SQL_SRCS = $(addprefix src/sql/,header.sql delaunay.sql diagnostics.sql voronoi.sql \
	tiled_internals.sql tiled.sql constrained.sql tin.sql contours_tiled.sql version.sql)
RASTER_SQL_SRCS = $(addprefix src/sql/,raster_header.sql raster.sql raster_tiled.sql)
POINTCLOUD_SQL_SRCS = src/sql/pointcloud.sql
DATA_built = tdc_delaunay--$(EXTVERSION).sql tdc_delaunay_raster--$(RASTER_EXTVERSION).sql \
	tdc_delaunay_pointcloud--$(POINTCLOUD_EXTVERSION).sql
DATA = tdc_delaunay--0.1.0.sql tdc_delaunay--0.1.0--1.0.0.sql tdc_delaunay--1.0.0.sql \
	tdc_delaunay--1.0.0--1.1.0.sql tdc_delaunay--1.1.0.sql tdc_delaunay--1.1.0--1.2.0.sql \
	tdc_delaunay_raster--1.1.0.sql tdc_delaunay_raster--1.1.0--1.2.0.sql

CORE_SRCS = $(sort $(wildcard src/core/*/*.c))
PG_SRCS = $(sort $(wildcard src/pg/*/*.c))
CLI_SRCS = $(sort $(wildcard src/cli/*.c))
CORE_HDRS = $(wildcard src/core/*.h src/core/*/*.h)
OBJS = $(CORE_SRCS:.c=.o) $(PG_SRCS:.c=.o)

# tdc_pointcloud and tdc_pointcloud_tiled need pgpointcloud on the server:
# they run only where the server has pointcloud's control file (pg_config's
# sharedir), and the suite says when they are left out (scripts/test.sh).
PC_INSTALLED = $(wildcard $(shell $(PG_CONFIG) --sharedir 2>/dev/null)/extension/pointcloud.control)
REGRESS = $(filter-out $(if $(PC_INSTALLED),,tdc_pointcloud tdc_pointcloud_tiled),$(basename $(notdir $(sort $(wildcard sql/*.sql)))))
REGRESS_OPTS = --inputdir=. --outputdir=build/regress

PG_CPPFLAGS = -Isrc/core -Isrc/pg -pthread
# zlib: the dimensional pcpatch compression of that name (pcpatch_read.c)
SHLIB_LINK = -pthread -lm -lz
EXTRA_CLEAN = tdc build

# Exact predicates: never -ffast-math, -Ofast or -ffp-contract=fast.
CORE_CFLAGS = -std=c11 -D_GNU_SOURCE -O2 -g -Wall -Wextra -Wno-unused-parameter \
	-ffp-contract=off -pthread -Isrc/core
CC_CORE ?= cc

TEST_SRCS = $(sort $(wildcard test/test_*.c))
# The core suite reads test/fixtures; the tree's own path makes it find them
# from any current directory.
TEST_CFLAGS = -Itest -DTDC_SOURCE_DIR='"$(CURDIR)"'

.PHONY: check-core check-core-asan check-core-tsan test demo bench bench-tin bench-coverage

# ./tdc writes GeoTIFF through GDAL (src/cli/geotiff.c; Debian: libgdal-dev).
# It compiles against GDAL's headers and loads the library it names
# (TDC_GDAL_SONAME, read from the libgdal.so the compiler finds) only to
# write a GeoTIFF: linking it would add some 30 MB to every run's resident
# size.  The extension's library never uses GDAL.  GDAL's headers are
# system headers here: their warnings are not ours.
GDAL_CFLAGS ?= $(patsubst -I%,-isystem %,$(shell pkg-config --cflags gdal 2>/dev/null || gdal-config --cflags 2>/dev/null))
GDAL_SONAME ?= $(shell objdump -p "$$($(firstword $(CC_CORE)) -print-file-name=libgdal.so)" 2>/dev/null | \
	awk '$$1 == "SONAME" { print $$2 }')
GDAL_BUILD = $(GDAL_CFLAGS) -DTDC_GDAL_SONAME='"$(GDAL_SONAME)"'
GDAL_CHECK = @[ -n "$(GDAL_SONAME)" ] || { echo "./tdc needs GDAL's headers and library: install libgdal-dev (or set GDAL_CFLAGS and GDAL_SONAME)" >&2; exit 1; }

tdc: $(CLI_SRCS) $(wildcard src/cli/*.h) $(CORE_SRCS) $(CORE_HDRS)
	$(GDAL_CHECK)
	$(CC_CORE) $(CORE_CFLAGS) $(GDAL_BUILD) -o $@ $(CLI_SRCS) $(CORE_SRCS) -ldl -lm

# The GeoTIFF writer fed rows in pieces (test/cli_geotiff.sh)
build/geotiff_rows: test/geotiff_rows.c src/cli/geotiff.c src/cli/cli.h
	$(GDAL_CHECK)
	@mkdir -p build
	$(CC_CORE) $(CORE_CFLAGS) $(GDAL_BUILD) -Isrc/cli -o $@ test/geotiff_rows.c src/cli/geotiff.c -ldl -lm

# ./tdc's "%.17g" without printf against the C library (test/cli_fmt_g17.sh)
build/fmt_g17: test/fmt_g17.c test/splitmix.h src/cli/fmt_g17.c src/cli/cli.h
	@mkdir -p build
	$(CC_CORE) $(CORE_CFLAGS) -Isrc/cli -Itest -o $@ test/fmt_g17.c src/cli/fmt_g17.c -lm

build/test_core: $(TEST_SRCS) $(wildcard test/*.h) $(CORE_SRCS) $(CORE_HDRS)
	@mkdir -p build
	$(CC_CORE) $(CORE_CFLAGS) $(TEST_CFLAGS) -o $@ $(TEST_SRCS) $(CORE_SRCS) -lgmp -lm

# The constrained tests compare with CGAL when its headers are installed
# (Debian: libcgal-dev); the reference is a test tool, never linked in.
CGAL_CDT = $(if $(wildcard /usr/include/CGAL/Constrained_Delaunay_triangulation_2.h),build/cgal_cdt)

build/cgal_cdt: test/cgal_cdt.cpp
	@mkdir -p build
	$(CXX) -O2 -DNDEBUG -DCGAL_NDEBUG -o $@ $< -lgmp -lmpfr

# The natural neighbour tests compare with CGAL's natural_neighbor_coordinates_2
# with exact constructions, the same way (test/cgal_nn.cpp).
CGAL_NN = $(if $(wildcard /usr/include/CGAL/natural_neighbor_coordinates_2.h),build/cgal_nn)

build/cgal_nn: test/cgal_nn.cpp
	@mkdir -p build
	$(CXX) -O2 -DNDEBUG -DCGAL_NDEBUG -o $@ $< -lgmp -lmpfr

# The breakline reference (test/cgal_linear.cpp): linear on CGAL's constrained
# Delaunay triangulation, exact; it made test/fixtures/tin-reference.txt,
# which the core suite checks against it again.
CGAL_LINEAR = $(if $(CGAL_CDT),build/cgal_linear)

build/cgal_linear: test/cgal_linear.cpp
	@mkdir -p build
	$(CXX) -O2 -DNDEBUG -DCGAL_NDEBUG -o $@ $< -lgmp -lmpfr

check-core: build/test_core $(CGAL_CDT) $(CGAL_NN) $(CGAL_LINEAR)
	build/test_core

# The exact arbiter of ./tdc's grids and contours (test/cli.sh): GMP.
build/tin_arbiter: test/tin_arbiter.c
	@mkdir -p build
	$(CC_CORE) $(CORE_CFLAGS) -o $@ $< -lgmp -lm

build/test_core_asan: $(TEST_SRCS) $(wildcard test/*.h) $(CORE_SRCS) $(CORE_HDRS)
	@mkdir -p build
	clang $(filter-out -O2,$(CORE_CFLAGS)) -O1 -fno-omit-frame-pointer \
		-fsanitize=address,undefined -fno-sanitize-recover=all $(TEST_CFLAGS) -o $@ \
		$(TEST_SRCS) $(CORE_SRCS) -lgmp -lm

check-core-asan: build/test_core_asan
	build/test_core_asan --quick

build/test_core_tsan: $(TEST_SRCS) $(wildcard test/*.h) $(CORE_SRCS) $(CORE_HDRS)
	@mkdir -p build
	clang $(filter-out -O2,$(CORE_CFLAGS)) -O1 -fsanitize=thread $(TEST_CFLAGS) -o $@ \
		$(TEST_SRCS) $(CORE_SRCS) -lgmp -lm

check-core-tsan: build/test_core_tsan
	build/test_core_tsan --quick

test:
	bash scripts/test.sh

# A blank line between the files; written whole or not at all.
tdc_delaunay--$(EXTVERSION).sql: $(SQL_SRCS)
	awk 'FNR == 1 && NR > 1 { print "" } { print }' $^ > $@.tmp
	mv $@.tmp $@

tdc_delaunay_raster--$(RASTER_EXTVERSION).sql: $(RASTER_SQL_SRCS)
	awk 'FNR == 1 && NR > 1 { print "" } { print }' $^ > $@.tmp
	mv $@.tmp $@

tdc_delaunay_pointcloud--$(POINTCLOUD_EXTVERSION).sql: $(POINTCLOUD_SQL_SRCS)
	awk 'FNR == 1 && NR > 1 { print "" } { print }' $^ > $@.tmp
	mv $@.tmp $@

demo:
	bash scripts/demo.sh

bench:
	bash bench/run.sh

# bench/run.sh with its part G only: build, install, a throw-away cluster
bench-tin:
	BENCH_TIN=1 BENCH_SKIP_CORE=1 BENCH_SKIP_TILED=1 BENCH_SKIP_SQL=1 BENCH_SKIP_SWEEP=1 bash bench/run.sh

# bench/run.sh with its part I only (bench/coverage_bench.sh, issue 40)
bench-coverage:
	BENCH_COVERAGE=1 BENCH_SKIP_CORE=1 BENCH_SKIP_TILED=1 BENCH_SKIP_SQL=1 BENCH_SKIP_SWEEP=1 \
		BENCH_SKIP_FIRST=1 bash bench/run.sh

# PGXS is optional: the core, ./tdc and its tests build without PostgreSQL.
PG_CONFIG ?= pg_config
PGXS := $(shell $(PG_CONFIG) --pgxs 2>/dev/null)
ifneq ($(PGXS),)
include $(PGXS)
# pg_regress 17 no longer creates missing parents of --outputdir.
installcheck: | build/regress
build/regress:
	mkdir -p $@
# Plain `make` builds the extension (the first rule above is ./tdc).
.DEFAULT_GOAL := all
# Core objects inside the extension are built with the core's language level.
src/core/%.o: src/core/%.c $(CORE_HDRS)
	$(CC) $(CFLAGS) -std=c11 -D_GNU_SOURCE -ffp-contract=off -pthread -Isrc/core -c -o $@ $<
# PGXS does not track headers: a changed struct must rebuild every user.
$(PG_SRCS:.c=.o): $(wildcard src/pg/*.h src/pg/*/*.h) src/core/tdc.h src/core/tdc_bounded.h
# tdc_delaunay_full_version() reports the PostGIS found here at build time:
# the default_version of its control file (the library does not compile
# against PostGIS, so nothing more precise exists), or "unknown".
POSTGIS_BUILD_VERSION := $(shell sed -n "s/^default_version *= *'\([^']*\)'.*/\1/p" \
	'$(shell $(PG_CONFIG) --sharedir)/extension/postgis.control' 2>/dev/null)
# The pcpatch reader scales values as pgpointcloud does, in two roundings.
src/pg/formats/pcpatch_read.o: override CFLAGS += -ffp-contract=off
# (the .bc is the JIT's bitcode of the same file)
src/pg/fn/version.o src/pg/fn/version.bc: override CPPFLAGS += \
	-DTDC_LIB_VERSION='"$(EXTVERSION)"' -DTDC_BUILD_POSTGIS='"$(or $(POSTGIS_BUILD_VERSION),unknown)"'
src/pg/fn/version.o src/pg/fn/version.bc: Makefile
else
all: tdc
endif

# ---------------------------------------------------------------------------
# Fuzzing (fuzz/README.md): libFuzzer targets built with clang,
# -fsanitize=fuzzer,address,undefined.
#
#   make fuzz                       build build/fuzz/fuzz_{core,gserialized,state,voronoi,cdt,raster,pcpatch}
#   make fuzz-run [FUZZ_SECONDS=60] run each from its seed corpus, summary line
#
# The PostgreSQL-side targets compile src/pg sources against the server
# headers with the shims in fuzz/pg_shim.c (no server needed).
FUZZ_SECONDS ?= 60
FUZZ_CC ?= clang
FUZZ_TARGETS = fuzz_core fuzz_gserialized fuzz_state fuzz_voronoi fuzz_cdt fuzz_raster fuzz_pcpatch
FUZZ_RUN_TARGETS = fuzz_core fuzz_gserialized fuzz_state fuzz_voronoi fuzz_cdt fuzz_raster fuzz_pcpatch
FUZZ_CFLAGS = -g -O1 -fno-omit-frame-pointer -D_GNU_SOURCE -ffp-contract=off \
	-pthread -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
	-Wall -Wno-unused-parameter -Wno-missing-field-initializers
FUZZ_PG_CFLAGS = -DUSE_ASSERT_CHECKING -Wno-ignored-attributes \
	-I$(shell $(PG_CONFIG) --includedir-server 2>/dev/null) -Isrc/pg -Ifuzz
# The core is compiled once, instrumented, into build/fuzz/core.a, which every
# target links: six targets compiling the whole core each cost a fresh CI
# run minutes of CPU for nothing.
FUZZ_CORE_OBJS = $(patsubst src/core/%.c,build/fuzz/core/%.o,$(CORE_SRCS))
FUZZ_CORE_LIB = build/fuzz/core.a
FUZZ_CORE_DEPS = $(FUZZ_CORE_LIB)

build/fuzz/core/%.o: src/core/%.c $(CORE_HDRS)
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_CFLAGS) -std=c11 -Isrc/core -c -o $@ $<

$(FUZZ_CORE_LIB): $(FUZZ_CORE_OBJS)
	rm -f $@
	ar rcs $@ $^

.PHONY: fuzz fuzz-run

fuzz: $(addprefix build/fuzz/,$(FUZZ_TARGETS))

build/fuzz/fuzz_core: fuzz/fuzz_core.c test/xy_oracle.h test/splitmix.h $(FUZZ_CORE_DEPS)
	@mkdir -p build/fuzz
	$(FUZZ_CC) $(FUZZ_CFLAGS) -std=c11 -Isrc/core -o $@ fuzz/fuzz_core.c $(FUZZ_CORE_LIB) -lm

build/fuzz/fuzz_cdt: fuzz/fuzz_cdt.c $(FUZZ_CORE_DEPS)
	@mkdir -p build/fuzz
	$(FUZZ_CC) $(FUZZ_CFLAGS) -std=c11 -Isrc/core -o $@ fuzz/fuzz_cdt.c $(FUZZ_CORE_LIB) -lm

# The reader and writers, and the aggregate state, each with the point buffer.
FUZZ_GSER_SRCS = src/pg/formats/gser_read.c src/pg/formats/gser_write.c src/pg/runtime/pointbuf.c
# fuzz_state also takes the TIN aggregates' states (fuzz_state_tin.c): their
# entry points, and what their serial, deserial and combine functions call
# (their shared samples in tin_agg.c, the method parser in fn_raster.c,
# which brings the raster and geometry readers and writers, and the
# breaklines' segment list in seglist.c);
# pg_shim_agg.c stands in for tin_run.c, run.c's wait loop and the rest.
FUZZ_STATE_SRCS = $(addprefix src/pg/runtime/,agg_state.c seglist.c) \
	$(addprefix src/pg/fn/,tin_agg.c fn_contours_agg.c fn_drape_agg.c fn_raster_agg.c fn_raster.c) \
	$(addprefix src/pg/formats/,raster_read.c raster_write.c gser_contour.c gser_drape.c) \
	$(FUZZ_GSER_SRCS)
FUZZ_PG_DEPS = fuzz/pg_shim.c fuzz/pg_shim.h src/pg/tdc_pg.h src/pg/pg_version_compat.h \
	src/pg/formats/gser_format.h

build/fuzz/fuzz_voronoi: fuzz/fuzz_voronoi.c $(FUZZ_CORE_DEPS)
	@mkdir -p build/fuzz
	$(FUZZ_CC) $(FUZZ_CFLAGS) -std=c11 -Isrc/core -o $@ fuzz/fuzz_voronoi.c $(FUZZ_CORE_LIB) -lm

build/fuzz/fuzz_gserialized: fuzz/fuzz_gserialized.c $(FUZZ_GSER_SRCS) $(FUZZ_PG_DEPS) \
		$(FUZZ_CORE_DEPS)
	@mkdir -p build/fuzz
	$(FUZZ_CC) $(FUZZ_CFLAGS) $(FUZZ_PG_CFLAGS) -Isrc/core -o $@ fuzz/fuzz_gserialized.c \
		fuzz/pg_shim.c $(FUZZ_GSER_SRCS) $(FUZZ_CORE_LIB) -lm

# The raster reader and writer need nothing of the core.
FUZZ_RASTER_SRCS = src/pg/formats/raster_read.c src/pg/formats/raster_write.c

build/fuzz/fuzz_raster: fuzz/fuzz_raster.c $(FUZZ_RASTER_SRCS) $(FUZZ_PG_DEPS) src/pg/formats/raster_format.h
	@mkdir -p build/fuzz
	$(FUZZ_CC) $(FUZZ_CFLAGS) $(FUZZ_PG_CFLAGS) -Isrc/core -o $@ fuzz/fuzz_raster.c \
		fuzz/pg_shim.c $(FUZZ_RASTER_SRCS) -lm

# The pcpatch reader is pure C: no shims, no core; zlib for its blocks.
FUZZ_PCPATCH_SRCS = src/pg/formats/pcpatch_read.c src/pg/formats/pcpatch_schema.c

build/fuzz/fuzz_pcpatch: fuzz/fuzz_pcpatch.c $(FUZZ_PCPATCH_SRCS) src/pg/formats/pcpatch_format.h
	@mkdir -p build/fuzz
	$(FUZZ_CC) $(FUZZ_CFLAGS) -std=c11 -Isrc/pg -o $@ fuzz/fuzz_pcpatch.c $(FUZZ_PCPATCH_SRCS) -lz -lm

build/fuzz/fuzz_state: fuzz/fuzz_state.c fuzz/fuzz_state_tin.c fuzz/fuzz_state.h \
		fuzz/pg_shim_agg.c $(FUZZ_STATE_SRCS) $(FUZZ_PG_DEPS) $(FUZZ_CORE_DEPS) \
		src/pg/formats/raster_format.h src/pg/fn/fn_raster.h
	@mkdir -p build/fuzz
	$(FUZZ_CC) $(FUZZ_CFLAGS) $(FUZZ_PG_CFLAGS) -Isrc/core -o $@ fuzz/fuzz_state.c \
		fuzz/fuzz_state_tin.c fuzz/pg_shim.c fuzz/pg_shim_agg.c $(FUZZ_STATE_SRCS) \
		$(FUZZ_CORE_LIB) -lm

fuzz-run: fuzz
	FUZZ_SECONDS=$(FUZZ_SECONDS) bash fuzz/run.sh $(FUZZ_RUN_TARGETS)

# Debian packages for this machine's PostgreSQL major, in build/deb/
# (scripts/deb.sh, debian/README.source).
.PHONY: deb
deb:
	bash scripts/deb.sh
