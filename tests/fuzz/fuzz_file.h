/*
 * fuzz_file.h - what every libFuzzer target of tests/fuzz shares: the
 * readers under test take file names, so each input is first written to a
 * file of the target's own temporary folder, which is removed at exit.
 */
#ifndef ILF_FUZZ_FILE_H
#define ILF_FUZZ_FILE_H

#include <stddef.h>
#include <stdint.h>

/**
 * Writes the size bytes of data to the file called name (no '/') in this
 * process's temporary folder, created on the first call.
 * @return the file's path, valid until the next call; aborts if it cannot be
 * written, since every later input would then test nothing.
 */
const char *fuzz_file_write(const char *name, const uint8_t *data, size_t size);

#endif /* ILF_FUZZ_FILE_H */
