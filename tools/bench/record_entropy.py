#!/usr/bin/env python3
"""What an entropy coder could take out of a .spg's node records.

usage: tools/bench/record_entropy.py MODEL.spg

Prints, per record field, its stored bits and its order-0 entropy over all
records (what a static per-field coder could reach), then the entropy of
each axis of a node's mean relative to its parent's, per tree depth, and of
a right child's mean predicted from its parent and its left sibling (2 x
parent - left: TOG05's count-weighted mix with equal counts). Reads format
versions 1 and 2 (docs/format.md); binary trees and octrees (the sibling
prediction only for binary trees).
"""
import math
import struct
import sys
from collections import Counter

NAMES = 'pos_x pos_y pos_z fp_theta fp_phi fp_psi sigma_p fn_theta fn_phi fn_psi sigma_n ' \
        'color_r color_g color_b fc_theta fc_phi fc_psi sigma_c'.split()


def entropy(counter):
    n = sum(counter.values())
    return -sum(c / n * math.log2(c / n) for c in counter.values())


def conditional(groups):
    n = sum(sum(c.values()) for c in groups.values())
    return sum(sum(c.values()) / n * entropy(c) for c in groups.values())


def main():
    if len(sys.argv) != 2 or sys.argv[1] in ('-h', '--help'):
        print(__doc__.strip())
        return 0 if len(sys.argv) == 2 else 2
    data = open(sys.argv[1], 'rb').read()
    if data[:4] != b'STPG':
        print(f'{sys.argv[1]}: not a .spg file', file=sys.stderr)
        return 1
    version = struct.unpack_from('<H', data, 4)[0]
    arity = data[8]
    bits = list(data[10:28])
    nodes = struct.unpack_from('<I', data, 28)[0]
    classes = struct.unpack_from('<HHH', data, 68)
    value = 4 if version == 1 else 2
    at = (76 if version == 1 else 100) + value * (3 * classes[0] + 2 * classes[1] + 3 * classes[2])
    record = (sum(bits) + 7) // 8
    records = data[len(data) - 4 - nodes * record:len(data) - 4]
    fields = []
    for i in range(nodes):
        v = int.from_bytes(records[i * record:(i + 1) * record], 'little')
        out, shift = [], 0
        for w in bits:
            out.append((v >> shift) & ((1 << w) - 1) if w else 0)
            shift += w
        fields.append(out)
    # The topology (§3): a bit a node (binary: has children) or 4 bits (octree: children).
    parent, depth, first = [0] * nodes, [0] * nodes, [0] * nodes
    following = 1
    for i in range(nodes):
        if arity == 2:
            children = 2 * ((data[at + (i >> 3)] >> (i & 7)) & 1)
        else:
            children = (data[at + (i >> 1)] >> (4 * (i & 1))) & 15
        first[i] = following
        for k in range(children):
            parent[following + k] = i
            depth[following + k] = depth[i] + 1
        following += children
    print(f'{sys.argv[1]}: {nodes:,} nodes, {record}-byte records')
    stored = total = 0
    for f, w in enumerate(bits):
        if not w:
            continue
        h = entropy(Counter(r[f] for r in fields))
        stored += w
        total += h
        print(f'  {NAMES[f]:9} {w:2} bits, order-0 entropy {h:5.2f}')
    print(f'  record   {stored} bits, order-0 entropy {total:.1f} ({100 * (1 - total / stored):.1f} % less)')
    relative = 0.0
    for axis in range(3):
        groups = {}
        for i in range(1, nodes):
            groups.setdefault(depth[i], Counter())[fields[i][axis] - fields[parent[i]][axis]] += 1
        h = conditional(groups)
        relative += h
        print(f'  {NAMES[axis]}: relative to the parent, per depth: {h:.2f} bits of {bits[axis]}')
    print(f'  mean relative to the parent: {relative:.1f} bits of {sum(bits[:3])}')
    if arity == 2:
        predicted = 0.0
        for axis in range(3):
            groups = {}
            for i in range(1, nodes):
                if i == first[parent[i]] + 1:  # a right child
                    guess = 2 * fields[parent[i]][axis] - fields[i - 1][axis]
                    groups.setdefault(depth[i], Counter())[fields[i][axis] - guess] += 1
            predicted += conditional(groups)
        print(f'  a right child\'s mean from its parent and left sibling: {predicted:.1f} bits of {sum(bits[:3])}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
