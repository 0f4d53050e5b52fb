/* Colours of a set of work nodes such that two nodes of one element never
 * share a colour, so that a pass may move the nodes of one colour at once
 * (the untangling, the interface nodes of several materials).
 * Jones-Plassmann: in each round, every uncoloured node whose priority beats
 * its uncoloured neighbours takes the smallest colour its neighbours lack;
 * the priorities are a hash of the node's lattice key (or of its position
 * off the lattice), so the colours depend neither on the threads nor on the
 * numbering. */
#ifndef MX_COLOURING_H
#define MX_COLOURING_H

#include <stddef.h>
#include <stdint.h>

#include "soa/mesh.h"

enum { MX_MAX_COLOURS = 256 };

/* work: the nw nodes; widx: work index of each node of M, UINT32_MAX
 * outside the set; inc / off: the elements of node v are inc[off[v] ..
 * off[v + 1]) (at least for the work nodes). colour[i] receives work node
 * i's colour. Returns the number of colours, -1 for more than
 * MX_MAX_COLOURS, -2 out of memory. */
/* What node v is, as a number independent of the numbering: a hash of its
 * lattice key, or of its position off the lattice (the colours' priority;
 * the cleaving's tie-breaks). */
uint64_t mx_node_identity(const mx_mesh *M, uint32_t v);
int mx_colour_nodes(const mx_mesh *M, const uint32_t *inc, const uint64_t *off,
                    const uint32_t *work, size_t nw, const uint32_t *widx, int16_t *colour);

#endif
