#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
# This file is part of Normal_orientation.
"""Real airborne LiDAR tiles for the open-scan checks of doc/global_orientation.md.

  las_tile.py to-xyz IN.las OUT.xyz
      Writes the points of an uncompressed LAS file (versions 1.0-1.4, point
      formats 0-10) as "x y z" lines, shifted by the header's minimum corner,
      and their classification codes (2 = ground, 6 = building) to OUT.xyz.cls,
      one per line.
  las_tile.py up-share ORIENTED.xyz OUT.xyz.cls
      For the normals within 60 degrees of vertical (|nz| >= 0.5: ground,
      roofs, canopy), prints the share that faces up (nz > 0), over all of them
      and per class.  Airborne scans see every such surface from above.

Standard library only (no numpy), so that it runs wherever Python 3 does.
"""
import struct
import sys


def to_xyz(path, out):
    with open(path, 'rb') as f:
        b = f.read()
    if b[:4] != b'LASF':
        sys.exit('las_tile.py: %s is not a LAS file' % path)
    version = (b[24], b[25])
    offset = struct.unpack_from('<I', b, 96)[0]
    fmt = b[104] & 0x3f
    if b[104] & 0x80:
        sys.exit('las_tile.py: %s is compressed (LAZ); decompress it first' % path)
    length = struct.unpack_from('<H', b, 105)[0]
    n = struct.unpack_from('<I', b, 107)[0]
    if n == 0 and version >= (1, 4):
        n = struct.unpack_from('<Q', b, 247)[0]
    scale = struct.unpack_from('<3d', b, 131)
    shift = struct.unpack_from('<3d', b, 155)
    low = (struct.unpack_from('<d', b, 187)[0], struct.unpack_from('<d', b, 203)[0],
           struct.unpack_from('<d', b, 219)[0])
    if offset + n * length > len(b):
        sys.exit('las_tile.py: %s is truncated' % path)
    with open(out, 'w') as xyz, open(out + '.cls', 'w') as cls:
        for i in range(n):
            r = offset + i * length
            x, y, z = struct.unpack_from('<3i', b, r)
            code = b[r + 16] if fmt >= 6 else b[r + 15] & 31
            xyz.write('%.3f %.3f %.3f\n' % (x * scale[0] + shift[0] - low[0], y * scale[1] + shift[1] - low[1],
                                            z * scale[2] + shift[2] - low[2]))
            cls.write('%d\n' % code)
    print('%s: LAS %d.%d, point format %d, %d points' % (path, version[0], version[1], fmt, n))


def up_share(oriented, classes):
    with open(classes) as f:
        codes = [int(line) for line in f]
    counts = {}
    with open(oriented) as f:
        for i, line in enumerate(f):
            nz = float(line.split()[5])
            if abs(nz) < 0.5:
                continue
            for key in ('all', codes[i]):
                up, total = counts.get(key, (0, 0))
                counts[key] = (up + (nz > 0.0), total + 1)
    names = {2: 'ground', 6: 'building'}
    for key in ['all'] + sorted(k for k in counts if k != 'all'):
        up, total = counts[key]
        label = key if key == 'all' else 'class %d%s' % (key, ' (%s)' % names[key] if key in names else '')
        print('%s: %d of %d near-horizontal normals face up (%.2f%%)' % (label, up, total, 100.0 * up / total))


if __name__ == '__main__':
    if len(sys.argv) == 4 and sys.argv[1] == 'to-xyz':
        to_xyz(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 4 and sys.argv[1] == 'up-share':
        up_share(sys.argv[2], sys.argv[3])
    else:
        sys.exit(__doc__)
