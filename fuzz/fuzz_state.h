/*
 * fuzz_state.h
 *		What fuzz_state.c and fuzz_state_tin.c share: one target, the
 *		first state's magic number picking the aggregate.
 */
#ifndef FUZZ_STATE_H
#define FUZZ_STATE_H

/* Report a finding (abort(), which libFuzzer records as a crash). */
pg_noreturn extern void fuzz_state_fail(const char *what, const char *detail);

/* size bytes as a plain bytea with a 4-byte header (malloc'd) */
extern bytea *fuzz_state_bytea(const uint8 *data, size_t size);

/*
 * The TIN aggregates' checks, when the first state a starts with the magic
 * of ST_TDCContours, ST_TDCDrape or ST_TDCInterpolate; false otherwise.
 */
extern bool fuzz_state_tin(const uint8 *a, size_t alen, const uint8 *b, size_t blen);

#endif							/* FUZZ_STATE_H */
