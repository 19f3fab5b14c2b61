/* firmware-core from C on a Cortex-M4F (QEMU mps2-an386): the same vectors as the Rust
 * harness (firmware-core/qemu-test), printed as f32 bits and compared bit for bit with
 * the host's f32 evaluation by `cargo xtask embedded`; then the refusals. */
#include <stdint.h>
#include "firmware_core.h"

void semihost_puts(const char *s);

/* Written by `cargo xtask embedded` (c-data.c): the PWL blob from `host-fit fit`, the
 * physics blob from `host-fit diagnose --out`, the golden blob with 8 discovered terms,
 * the input table (ux uy uz temp dt, f32 LE: each sample on its own time step, s). */
extern const uint8_t fc_test_blob[], fc_test_blob_phys[], fc_test_blob_terms[], fc_test_inputs[];
extern const uint32_t fc_test_blob_len, fc_test_blob_phys_len, fc_test_blob_terms_len,
    fc_test_inputs_len;

static char line[96];
static unsigned pos;

static void put(const char *s) { while (*s && pos < sizeof line - 2) line[pos++] = *s++; }
static void put_hex(uint32_t v) {
    for (int i = 7; i >= 0; i--) line[pos++] = "0123456789abcdef"[(v >> (4 * i)) & 0xF];
}
static void put_dec(uint32_t v) {
    char d[11];
    int n = 0;
    do { d[n++] = (char)('0' + v % 10); v /= 10; } while (v);
    while (n) line[pos++] = d[--n];
}
static void flush(void) { line[pos++] = '\n'; line[pos] = 0; semihost_puts(line); pos = 0; }
static uint32_t bits(float f) { union { float f; uint32_t u; } c = { f }; return c.u; }
static float input(uint32_t i, uint32_t k) {
    union { uint32_t u; float f; } c;
    const uint8_t *p = fc_test_inputs + 20 * i + 4 * k;
    c.u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    return c.f;
}

static const char *const tags[3] = {"m1", "m2full", "m2simp"};
static const uint32_t methods[3] = {FC_METHOD_CONSTANTS, FC_METHOD_RESULT_FULL,
                                    FC_METHOD_RESULT_SIMPLIFIED};
static fc_blob blob;
static fc_compensator comp;

static int run(const uint8_t *bytes, uint32_t len, const char *prefix) {
    int32_t rc = fc_blob_open(&blob, bytes, len);
    if (rc != FC_OK) {
        put("error: blob refused, code "); put_dec((uint32_t)rc); flush();
        return 1;
    }
    for (int m = 0; m < 3; m++) {
        /* made for a 100 Hz MCU; every input carries its own time step */
        if (fc_compensator_init(&comp, &blob, methods[m], 0.01f) != FC_OK) {
            put("error: compensator refused"); flush();
            return 1;
        }
        for (uint32_t i = 0; i < fc_test_inputs_len / 20; i++) {
            float u[3] = {input(i, 0), input(i, 1), input(i, 2)}, a[3];
            uint32_t st = fc_compensate_dt(&comp, u, input(i, 3), input(i, 4), a);
            put("vec "); put(prefix); put(tags[m]); put(" "); put_dec(i);
            for (int k = 0; k < 3; k++) { put(" "); put_hex(bits(a[k])); }
            put(" "); put_dec(st); flush();
        }
    }
    return 0;
}

/* A blob cut short, and one with a flipped version bit, in RAM: each refused with its
 * own code. */
static uint8_t copy[1028];
static int refusals(void) {
    uint32_t n = fc_test_blob_len < sizeof copy ? fc_test_blob_len : sizeof copy;
    for (uint32_t i = 0; i < n; i++) copy[i] = fc_test_blob[i];
    int32_t truncated = fc_blob_open(&blob, copy, n - 1);
    copy[4] ^= 1;
    int32_t flipped = fc_blob_open(&blob, copy, n);
    put("refusals truncated "); put_dec((uint32_t)truncated);
    put(" flipped-version "); put_dec((uint32_t)flipped); flush();
    return truncated == FC_ERR_TRUNCATED && flipped == FC_ERR_CRC ? 0 : 1;
}

/* The golden blob's discovered terms read back: 8 of them, the first a_x*a_y on z, and
 * an index past the table refused. */
static int terms(void) {
    uint32_t n = 0;
    fc_term t;
    if (fc_blob_open(&blob, fc_test_blob_terms, fc_test_blob_terms_len) != FC_OK) return 1;
    int32_t rc = fc_blob_term_count(&blob, &n);
    int32_t first = fc_blob_term(&blob, 0, &t);
    int32_t past = fc_blob_term(&blob, n, &t);
    fc_blob_term(&blob, 0, &t);
    put("terms "); put_dec(n);
    put(" first "); put_dec(t.axis);
    for (int k = 0; k < 3; k++) { put(" "); put_dec(t.factors[k]); }
    flush();
    return rc == FC_OK && first == FC_OK && past == FC_ERR_INDEX && n == FC_MAX_TERMS &&
                   t.axis == 2 && t.factors[0] == FC_FACTOR_AX && t.factors[1] == FC_FACTOR_AY &&
                   t.factors[2] == FC_FACTOR_NONE
               ? 0
               : 1;
}

int main(void) {
    int bad = run(fc_test_blob, fc_test_blob_len, "");
    bad |= run(fc_test_blob_phys, fc_test_blob_phys_len, "p");
    bad |= run(fc_test_blob_terms, fc_test_blob_terms_len, "t");
    bad |= terms();
    bad |= refusals();
    put(bad ? "failed" : "done"); flush();
    return bad;
}
