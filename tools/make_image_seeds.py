#!/usr/bin/env python3
"""Writes the seeds of the label image fuzzers (tools/fuzz.sh: image_nii,
image_niigz, image_mha, image_inr, image_inrgz) into tools/fuzz_seeds/: small
valid images, headers written field by field from the specifications
(nifti1.h, nifti2.h, MetaIO's keys, the INRIA header), each under 8192 bytes
(fuzz.sh's -max_len).

    python3 tools/make_image_seeds.py [SEEDS_DIR]"""
import gzip
import math
import os
import struct
import sys
import zlib

OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "fuzz_seeds")
NX, NY, NZ = 4, 3, 5

# (nifti code, struct letter, MetaImage name, INR TYPE, bits)
TYPES = {
    "u8": (2, "B", "MET_UCHAR", "unsigned fixed", 8),
    "i8": (256, "b", "MET_CHAR", "signed fixed", 8),
    "i16": (4, "h", "MET_SHORT", "signed fixed", 16),
    "u16": (512, "H", "MET_USHORT", "unsigned fixed", 16),
    "i32": (8, "i", "MET_INT", "signed fixed", 32),
    "u32": (768, "I", "MET_UINT", "unsigned fixed", 32),
    "f32": (16, "f", "MET_FLOAT", "float", 32),
    "f64": (64, "d", "MET_DOUBLE", "float", 64),
}


def voxels(t, big):
    letter = TYPES[t][1]
    vals = [(i + 2 * j + 3 * k) % 5 for k in range(NZ) for j in range(NY) for i in range(NX)]
    if letter in "fd":
        vals = [v + (0.25 if n % 7 == 0 else 0) for n, v in enumerate(vals)]
    return struct.pack((">" if big else "<") + letter * len(vals), *vals)


def nifti1(t, big, xform):
    e = ">" if big else "<"
    h = bytearray(352)
    struct.pack_into(e + "i", h, 0, 348)
    struct.pack_into(e + "8h", h, 40, 3, NX, NY, NZ, 1, 1, 1, 1)
    struct.pack_into(e + "hh", h, 70, TYPES[t][0], TYPES[t][4])
    struct.pack_into(e + "8f", h, 76, -1, 0.5, 0.75, 1.25, 1, 1, 1, 1)
    struct.pack_into(e + "f", h, 108, 352)
    if xform == "sform":
        struct.pack_into(e + "hh", h, 252, 0, 1)
        struct.pack_into(e + "12f", h, 280, 0, 0, 1.5, 10, -0.5, 0, 0, 20, 0, 2, 0, 30)
    elif xform == "qform":
        struct.pack_into(e + "hh", h, 252, 1, 0)
        struct.pack_into(e + "6f", h, 256, 0, 0, math.sin(math.pi / 12), 5, -6, 7)
    elif xform == "scaled":
        struct.pack_into(e + "ff", h, 112, 2.0, 1.0)
    h[344:348] = b"n+1\0"
    return bytes(h) + voxels(t, big)


def nifti2(t, big, xform):
    e = ">" if big else "<"
    h = bytearray(544)
    struct.pack_into(e + "i", h, 0, 540)
    h[4:12] = b"n+2\0\r\n\x1a\n"
    struct.pack_into(e + "hh", h, 12, TYPES[t][0], TYPES[t][4])
    struct.pack_into(e + "8q", h, 16, 3, NX, NY, NZ, 1, 1, 1, 1)
    struct.pack_into(e + "8d", h, 104, 1, 0.5, 0.75, 1.25, 1, 1, 1, 1)
    struct.pack_into(e + "q", h, 168, 544)
    if xform == "sform":
        struct.pack_into(e + "ii", h, 344, 0, 2)
        struct.pack_into(e + "12d", h, 400, 1, 0.5, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0)
    elif xform == "qform":
        struct.pack_into(e + "ii", h, 344, 1, 0)
        struct.pack_into(e + "6d", h, 352, 0.5, 0, 0, 1, 2, 3)
    return bytes(h) + voxels(t, big)


def metaimage(t, big, compressed, extra=""):
    data = voxels(t, big)
    if compressed:
        data = zlib.compress(data)
    head = (
        "ObjectType = Image\nNDims = 3\n"
        f"DimSize = {NX} {NY} {NZ}\nElementType = {TYPES[t][2]}\n"
        f"BinaryData = True\nBinaryDataByteOrderMSB = {'True' if big else 'False'}\n"
        "ElementSpacing = 0.5 0.75 1.25\nOffset = 1 2 3\n" + extra +
        (f"CompressedData = True\nCompressedDataSize = {len(data)}\n" if compressed else "") +
        "ElementDataFile = LOCAL\n")
    return head.encode() + data


def inr(t, big, extra=""):
    head = (
        "#INRIMAGE-4#{\n"
        f"XDIM={NX}\nYDIM={NY}\nZDIM={NZ}\nVDIM=1\nTYPE={TYPES[t][3]}\nPIXSIZE={TYPES[t][4]} bits\n"
        f"SCALE=2**0\nCPU={'sun' if big else 'decm'}\nVX=0.5\nVY=0.75\nVZ=1.25\n" + extra)
    n = (len(head) + 4 + 255) // 256 * 256
    head = head + "\n" * (n - 4 - len(head)) + "##}\n"
    return head.encode() + voxels(t, big)


def save(target, name, data):
    d = os.path.join(OUT, target)
    os.makedirs(d, exist_ok=True)
    assert len(data) <= 8192, (name, len(data))
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def gz(data):
    return gzip.compress(data, mtime=0)


def main():
    nii = {
        "v1_u8_le": nifti1("u8", 0, ""),
        "v1_f32_be_sform": nifti1("f32", 1, "sform"),
        "v1_i16_le_qform": nifti1("i16", 0, "qform"),
        "v1_u16_be_scaled": nifti1("u16", 1, "scaled"),
        "v2_i32_le_sform": nifti2("i32", 0, "sform"),
        "v2_f64_be_qform": nifti2("f64", 1, "qform"),
        "v2_i8_le": nifti2("i8", 0, ""),
        "v2_u32_be": nifti2("u32", 1, ""),
    }
    for name, data in nii.items():
        save("image_nii", name + ".nii", data)
        save("image_niigz", name + ".nii.gz", gz(data))
    save("image_mha", "u8_le.mha", metaimage("u8", 0, False))
    save("image_mha", "i16_be.mha", metaimage("i16", 1, False, "TransformMatrix = 0 1 0 -1 0 0 0 0 1\n"))
    save("image_mha", "f32_le_z.mha", metaimage("f32", 0, True))
    save("image_mha", "u32_be_z.mha", metaimage("u32", 1, True, "Orientation = 0.866 0.5 0 -0.5 0.866 0 0 0 1\n"))
    save("image_mha", "f64_le.mha", metaimage("f64", 0, False, "ElementNumberOfChannels = 1\n"))
    for t, big in (("u8", 0), ("i16", 1), ("u32", 0), ("f32", 1), ("f64", 0), ("i8", 1)):
        data = inr(t, big, "XO=1\nYO=2\nZO=3\n" if t == "i16" else "")
        save("image_inr", f"{t}_{'be' if big else 'le'}.inr", data)
        save("image_inrgz", f"{t}_{'be' if big else 'le'}.inr.gz", gz(data))


main()
