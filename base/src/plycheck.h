/*
 * plycheck.h - internal to base's mesh importer (mesh_import.c): a structural check of PLY mesh
 * files made before assimp reads them.
 *
 * assimp trusts the counts a PLY file declares (elements in the header, the
 * length of every list in the body) and reserves memory for them before it
 * finds out that the file is far too short to hold them: a header claiming
 * 10^9 vertices costs minutes and gigabytes, a face claiming 4*10^9 indices
 * aborts the process. ilf__ply_check() walks the file's structure, as the
 * header describes it, against the bytes actually there, so that every count
 * assimp will allocate from is bounded by the file's size. It also refuses
 * the one valid layout assimp 5.2 misreads: binary data whose first byte is
 * a line end (0x0a), which assimp skips, reading every value after it one
 * byte late (assimp issue #5341).
 */
#ifndef ILF_PLYCHECK_H
#define ILF_PLYCHECK_H

#include <stddef.h>

/*
 * Checks the file at path if it is a PLY file (it starts with "ply" and a
 * line end); a file that assimp would read as PLY without being one (its
 * name ends in .ply, or it starts with "ply" in any letter case, but its
 * first line is not "ply") is refused; any other file passes untouched,
 * for assimp to judge.
 * @return 1 if the file is not PLY, or its header parses and its body holds
 * every element and list the header and the list counts promise; 0 with the
 * problem in why (why_size bytes), e.g. "PLY header declares 1000000000
 * 'vertex' elements, but only 27 bytes follow it".
 */
int ilf__ply_check(const char *path, char *why, size_t why_size);

#endif /* ILF_PLYCHECK_H */
