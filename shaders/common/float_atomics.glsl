// Float addition to storage-buffer words from many threads at once.
//
// Where the device has GL_NV_shader_atomic_float (NVIDIA's drivers and Mesa's both do), an addition
// is one atomic. Without it, a compare-and-swap loop on the word's bits: each thread retries until
// no other wrote in between, so with k threads on one word the work grows as k^2 — negligible on a
// few CPU threads, seconds on a GPU where a light-view map's photons pile onto a lampshade's few
// voxels. FLOAT_ADD_BY_COMPARE_AND_SWAP forces the loop (tests compare the two).
//
// A buffer of such words is declared with FLOAT_WORD as its element type and read and written
// through float_word_value() and float_word(); FLOAT_ADD_FUNCTION(name, array) defines
// `void name(uint index, float value)` that adds to array[index].
#extension GL_NV_shader_atomic_float : enable

#if defined(GL_NV_shader_atomic_float) && !defined(FLOAT_ADD_BY_COMPARE_AND_SWAP)
#define FLOAT_WORD float
float float_word_value(float word) { return word; }
float float_word(float value) { return value; }
#define FLOAT_ADD_FUNCTION(name, array)                       \
    void name(uint index, float value) {                      \
        if (value != 0.0) atomicAdd(array[index], value);     \
    }
#else
#define FLOAT_WORD uint
float float_word_value(uint word) { return uintBitsToFloat(word); }
uint float_word(float value) { return floatBitsToUint(value); }
// The attempt cap keeps a pathological pile-up from running without end; it is never reached in
// the bench scenes (k is at most tens of thousands).
#define FLOAT_ADD_FUNCTION(name, array)                                                                  \
    void name(uint index, float value) {                                                                 \
        if (value == 0.0) return;                                                                        \
        uint seen = array[index];                                                                        \
        for (int attempt = 0; attempt < 1000000; ++attempt) {                                            \
            uint expected = seen;                                                                        \
            seen = atomicCompSwap(array[index], expected, floatBitsToUint(uintBitsToFloat(expected) + value)); \
            if (seen == expected) break;                                                                 \
        }                                                                                                \
    }
#endif
