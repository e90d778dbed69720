"""Static cost of a SPIR-V shader module: ALU, texture, load/store and branch instructions.

Reads the binary module directly (SPIR-V 1.x specification, section 2.3 "Physical Layout of a
SPIR-V Module and Instruction": 5-word header, then instructions whose first word is
wordcount << 16 | opcode). Opcode numbers are those of the SPIR-V specification's "Instructions"
section (3.49 / 3.52 in the unified specification; the values are fixed across versions).

What is counted (straight-line, every instruction once: a loop body counts once, both sides of a
branch count; `loops` says how many loops were seen so the caller can flag the approximation):
- alu_ops: scalar arithmetic operations - each arithmetic, relational, logical, bit, conversion,
  derivative or GLSL.std.450 extended instruction weighs the component count of its result
  (OpDot the component count of its operands, matrix products rows x columns of the product).
- tex_fetches: OpImageSample*/OpImageFetch/OpImageGather/OpImageRead and their sparse forms.
- loads, stores: OpLoad, OpStore (memory or register spills alike: SPIR-V does not say which).
- branches: OpBranchConditional and OpSwitch.
- discard: OpKill, OpTerminateInvocation or OpDemoteToHelperInvocation present.
"""

import struct

SPIRV_MAGIC = 0x07230203

# Types (SPIR-V spec 3.49.6 "Type-Declaration Instructions").
OP_TYPE_BOOL, OP_TYPE_INT, OP_TYPE_FLOAT, OP_TYPE_VECTOR, OP_TYPE_MATRIX = 20, 21, 22, 23, 24
OP_EXT_INST = 12
OP_CONSTANT, OP_CONSTANT_COMPOSITE = 43, 44
OP_LOAD, OP_STORE = 61, 62
OP_DOT = 148
OP_VECTOR_TIMES_MATRIX, OP_MATRIX_TIMES_VECTOR, OP_MATRIX_TIMES_MATRIX = 144, 145, 146
OP_LOOP_MERGE = 246
OP_BRANCH_CONDITIONAL, OP_SWITCH = 250, 251
OP_KILL, OP_TERMINATE_INVOCATION, OP_DEMOTE = 252, 4416, 5380

# Conversion 109-124 (OpConvertFToU .. OpBitcast), arithmetic 126-152 (OpSNegate .. OpSMulExtended),
# relational and logical 154-191 (OpAny .. OpFUnordGreaterThanEqual), bit 194-205 (OpShiftRightLogical
# .. OpBitCount), derivative 207-215 (OpDPdx .. OpFwidthCoarse).
ALU_RANGES = ((109, 124), (126, 152), (154, 191), (194, 205), (207, 215))
# OpImageSampleImplicitLod 87 .. OpImageDrefGather 97, OpImageRead 98; sparse 305-315.
TEX_RANGES = ((87, 98), (305, 315))


def _in(op, ranges):
    return any(lo <= op <= hi for lo, hi in ranges)


class SpirvError(ValueError):
    """The bytes are not a SPIR-V module (bad magic, truncated instruction)."""


def shader_cost(data):
    """Counts of one module's instructions (see the module docstring); raises SpirvError."""
    if len(data) < 20 or len(data) % 4:
        raise SpirvError("not a SPIR-V module: %d bytes (needs a 5-word header and whole words)" % len(data))
    words = struct.unpack("<%dI" % (len(data) // 4), data)
    if words[0] != SPIRV_MAGIC:
        if struct.unpack(">I", data[:4])[0] == SPIRV_MAGIC:
            words = struct.unpack(">%dI" % (len(data) // 4), data)
        else:
            raise SpirvError("not a SPIR-V module: magic 0x%08x" % words[0])
    comps = {}      # type id -> scalar components (bool/int/float 1, vector n, matrix cols x rows)
    cols = {}       # matrix type id -> column count
    value_type = {}  # result id -> type id
    cost = {"alu_ops": 0, "tex_fetches": 0, "loads": 0, "stores": 0, "branches": 0, "loops": 0,
            "discard": False, "instructions": 0}
    i = 5
    while i < len(words):
        wc, op = words[i] >> 16, words[i] & 0xFFFF
        if wc == 0 or i + wc > len(words):
            raise SpirvError("truncated SPIR-V: instruction at word %d has word count %d" % (i, wc))
        ops = words[i + 1:i + wc]
        i += wc
        cost["instructions"] += 1
        if op in (OP_TYPE_BOOL, OP_TYPE_INT, OP_TYPE_FLOAT):
            comps[ops[0]] = 1
            continue
        if op == OP_TYPE_VECTOR:
            comps[ops[0]] = ops[2]
            continue
        if op == OP_TYPE_MATRIX:
            comps[ops[0]] = comps.get(ops[1], 1) * ops[2]
            cols[ops[0]] = ops[2]
            continue
        alu = _in(op, ALU_RANGES) or op == OP_EXT_INST
        if (alu or _in(op, TEX_RANGES) or op in (OP_LOAD, OP_CONSTANT, OP_CONSTANT_COMPOSITE)) and len(ops) >= 2:
            value_type[ops[1]] = ops[0]
        if alu and len(ops) >= 2:
            n = comps.get(ops[0], 1)
            if op == OP_DOT and len(ops) >= 4:
                n = max(comps.get(value_type.get(ops[2]), 1), comps.get(value_type.get(ops[3]), 1))
            elif op in (OP_MATRIX_TIMES_VECTOR, OP_VECTOR_TIMES_MATRIX, OP_MATRIX_TIMES_MATRIX) and len(ops) >= 3:
                # Multiply-adds: one per result component per term of the shared dimension.
                left = value_type.get(ops[2])
                inner = cols.get(left, 1) if op != OP_VECTOR_TIMES_MATRIX else comps.get(left, 1)
                n = comps.get(ops[0], 1) * inner
            cost["alu_ops"] += n
        elif _in(op, TEX_RANGES):
            cost["tex_fetches"] += 1
        elif op == OP_LOAD:
            cost["loads"] += 1
        elif op == OP_STORE:
            cost["stores"] += 1
        elif op in (OP_BRANCH_CONDITIONAL, OP_SWITCH):
            cost["branches"] += 1
        elif op == OP_LOOP_MERGE:
            cost["loops"] += 1
        elif op in (OP_KILL, OP_TERMINATE_INVOCATION, OP_DEMOTE):
            cost["discard"] = True
    return cost


if __name__ == "__main__":
    import json
    import sys
    for path in sys.argv[1:]:
        try:
            with open(path, "rb") as f:
                print(path, json.dumps(shader_cost(f.read())))
        except (OSError, SpirvError) as e:
            print("spirv_cost.py: %s: %s" % (path, e), file=sys.stderr)
            sys.exit(2)
