#!/usr/bin/python3
"""Static analysis of the MPS2 firmware image (uwbnav_mps2.elf + its map file).

  check      Fails (exit 1) when the image links the heap (malloc/free/sbrk,
             libstdc++'s operator new/delete), C++ exceptions, or when the
             estimator's per-sample path (everything Navigator::on_imu,
             on_range and output reach) calls soft-double helpers (__aeabi_d*,
             float<->double conversions, double libm functions), directly or
             inside library code it calls.
             Run after every link of the image (hal/mps2/CMakeLists.txt).
  footprint  Prints the footprint figures as JSON (flash/RAM per section, the
             largest RAM objects, the worst-case stack, soft-double use) for
             scripts/footprint.sh.

Method (docs/footprint.md): the call graph comes from the disassembly of the
linked image (bl/blx/b.w to symbols; blx/bx to a register is an indirect call,
resolved conservatively to every address-taken function); frame sizes come from
GCC's -fcallgraph-info=su (.ci files) for code compiled here and from the
prologue (push/vpush/sub sp) for library code. The stack bound is the deepest
path, plus one exception frame with FPU context for a fault at that point.
"""
import argparse
import bisect
import glob
import json
import os
import re
import struct
import subprocess
import sys

HEAP_SYMBOLS = {
    "malloc", "free", "calloc", "realloc", "memalign", "aligned_alloc", "posix_memalign",
    "sbrk", "_sbrk", "__malloc_sbrk_start",
}
EXCEPTION_SYMBOLS = {
    "__cxa_allocate_exception", "__cxa_throw", "__cxa_begin_catch", "__cxa_end_catch",
    "__cxa_rethrow", "__gxx_personality_v0", "_Unwind_Resume", "_Unwind_RaiseException",
}
# operator new/new[] in every variant (sized, aligned, nothrow): _Znwj*, _Znaj*.
NEW_RE = re.compile(r"^_Zn[wa]j")
DELETE_RE = re.compile(r"^_Zd[la]Pv")
# Soft-double helpers of the Arm run-time ABI and double-precision libm entry points.
SOFT_DOUBLE_RE = re.compile(r"^__aeabi_(d[a-z0-9]+|f2d|i2d|ui2d|l2d|ul2d)$")
DOUBLE_LIBM = {
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "exp2",
    "expm1", "log", "log2", "log10", "log1p", "pow", "sqrt", "cbrt", "hypot", "erf", "erfc",
    "fmod", "remainder", "floor", "ceil", "round", "lround", "llround", "trunc", "lgamma", "tgamma",
}
HOT_ROOT = "_ZN6uwbnav3App4tickEy"
# The estimator's per-sample entry points (mangled-name prefixes; clones included).
ESTIMATOR_ROOTS = ("_ZN6uwbnav9Navigator6on_imu", "_ZN6uwbnav9Navigator8on_range", "_ZN6uwbnav9Navigator6output")
INIT_ROOT = "_ZN6uwbnav3App4initEv"
ENTRY = "Reset_Handler"
# Exception entry: 8 words basic frame + 18 words FP context (S0-S15, FPSCR, reserved).
EXCEPTION_FRAME_BYTES = 104


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def is_soft_double(name):
    return bool(SOFT_DOUBLE_RE.match(name)) or name in DOUBLE_LIBM


class Image:
    def __init__(self, args):
        self.elf = args.elf
        self.nm = args.nm
        self.objdump = args.objdump
        self.functions = {}   # name -> (addr, size)
        self.by_addr = {}     # addr -> name
        self.objects = {}     # name -> (addr, size) data objects
        self._read_symbols()
        self.owner_ranges = self._read_map(args.map)
        self._starts = [r[0] for r in self.owner_ranges]
        self.members = self._read_archive_members(args.map)
        self.frames, self.frame_kind = self._read_frames(args.callgraph_dir)
        self.edges, self.indirect_callers, self.dynamic_sp = self._read_disassembly()
        self.address_taken = self._address_taken()

    def _read_symbols(self):
        for line in run([self.nm, "-S", "--defined-only", self.elf]).splitlines():
            parts = line.split()
            if len(parts) != 4:
                continue
            addr, size, kind, name = int(parts[0], 16), int(parts[1], 16), parts[2], parts[3]
            if kind in "tTwW":
                addr &= ~1
                self.functions.setdefault(name, (addr, size))
                self.by_addr.setdefault(addr, name)
            elif kind in "bBdDrR":
                self.objects[name] = (addr, size)

    @staticmethod
    def _read_archive_members(path):
        """member -> (referencing file, symbol) from the map's archive member list."""
        members = {}
        with open(path) as f:
            lines = f.read().split("Archive member included to satisfy reference by file (symbol)", 1)
        if len(lines) < 2:
            return members
        body = re.split(r"\n(Discarded input sections|Memory Configuration|Allocating common symbols)", lines[1])[0]
        entry_re = re.compile(r"^(\S.*?)\n?\s+(\S+) \((.+)\)$", re.M)
        for m in entry_re.finditer(body.strip("\n")):
            members[m.group(1).strip()] = (m.group(2), m.group(3))
        return members

    def pulled_in_by(self, member):
        """Chain of files that made the linker take `member` from its archive."""
        chain, seen = [], set()
        while member in self.members and member not in seen:
            seen.add(member)
            member, symbol = self.members[member]
            chain.append(f"{member} needs {symbol}")
            if ".a(" not in member or "libuwbnav" in member:
                break
        return chain

    @staticmethod
    def _read_map(path):
        """(start, end, input file) of every input section the linker kept."""
        ranges = []
        pending = None
        in_map = False
        line_re = re.compile(r"^ (\.\S+)?\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S.*)$")
        with open(path) as f:
            for line in f:
                if line.startswith("Linker script and memory map"):
                    in_map = True
                    continue
                if not in_map:
                    continue
                m = line_re.match(line.rstrip("\n"))
                if m and (m.group(1) or pending):
                    start, size = int(m.group(2), 16), int(m.group(3), 16)
                    if size > 0 and not m.group(4).startswith("load address"):
                        ranges.append((start, start + size, m.group(4).strip()))
                    pending = None
                    continue
                m2 = re.match(r"^ (\.\S+)$", line.rstrip("\n"))
                pending = m2.group(1) if m2 else None
        ranges.sort()
        return ranges

    def owner(self, name):
        """Input file (object or archive member) that defined the symbol, from the map."""
        addr = self.functions.get(name, self.objects.get(name, (None, 0)))[0]
        if addr is None:
            return ""
        i = bisect.bisect_right(self._starts, addr) - 1
        while i >= 0 and self.owner_ranges[i][0] <= addr:
            start, end, path = self.owner_ranges[i]
            if addr < end:
                return path
            i -= 1
        return ""

    @staticmethod
    def _read_frames(build_dir):
        frames, kinds = {}, {}
        node_re = re.compile(r'node: \{ title: "([^"]+)" label: "[^"]*\\n(\d+) bytes \(([a-z,]+)\)"')
        for path in glob.glob(os.path.join(build_dir, "**", "*.ci"), recursive=True):
            with open(path, errors="replace") as f:
                for m in node_re.finditer(f.read()):
                    name, size, kind = m.group(1), int(m.group(2)), m.group(3)
                    if size >= frames.get(name, -1):
                        frames[name], kinds[name] = size, kind
        return frames, kinds

    def _read_disassembly(self):
        edges = {}
        indirect = set()
        dynamic = set()
        prologue = {}
        current = None
        head_re = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
        insn_re = re.compile(r"^\s+[0-9a-f]+:\s+(\S+)\s*(.*)$")
        target_re = re.compile(r"<([^>+]+)(\+0x[0-9a-f]+)?>")
        out = run([self.objdump, "-d", "--no-show-raw-insn", self.elf])
        for line in out.splitlines():
            h = head_re.match(line)
            if h:
                current = h.group(2)
                edges.setdefault(current, set())
                prologue.setdefault(current, 0)
                continue
            m = insn_re.match(line)
            if not m or current is None:
                continue
            op, operands = m.group(1), m.group(2).split(";")[0].split("@")[0].strip()
            base = op.split(".")[0]
            if base in ("bl", "blx", "b", "bx") or (base.startswith("b") and base[1:] in CONDITIONS):
                t = target_re.search(operands)
                if t and not t.group(2) and t.group(1) != current and t.group(1) in self.functions:
                    edges[current].add(t.group(1))
                elif base in ("blx", "bx") and re.match(r"^(r\d+|ip|sl|fp)$", operands):
                    indirect.add(current)
            elif base in ("push", "stmdb", "stmfd") and (base == "push" or operands.startswith("sp!")):
                prologue[current] += 4 * count_registers(operands)
            elif base in ("vpush", "vstmdb") and (base == "vpush" or operands.startswith("sp!")):
                prologue[current] += count_fp_bytes(operands)
            elif base in ("sub", "subw") and re.match(r"^sp,\s*(sp,\s*)?#", operands):
                prologue[current] += int(operands.split("#")[1].split()[0], 0)
            elif base in ("sub", "subw") and re.match(r"^sp,\s*(sp,\s*)?r", operands):
                dynamic.add(current)
        self.prologue = prologue
        return edges, indirect, dynamic

    def _address_taken(self):
        """Functions whose address (Thumb bit set) is stored in the image's data or literals."""
        with open(self.elf, "rb") as f:
            data = f.read()
        shoff, = struct.unpack_from("<I", data, 0x20)
        shentsize, shnum = struct.unpack_from("<HH", data, 0x2E)
        thumb_addrs = {addr | 1: name for name, (addr, _) in self.functions.items()}
        taken = set()
        for i in range(shnum):
            _, sh_type, flags, _, offset, size = struct.unpack_from("<IIIIII", data, shoff + i * shentsize)
            if sh_type != 1 or not flags & 2:  # PROGBITS, ALLOC
                continue
            for off in range(offset, offset + size - 3, 4):
                word, = struct.unpack_from("<I", data, off)
                if word in thumb_addrs:
                    taken.add(thumb_addrs[word])
        vectors = {ENTRY, "Fault_Handler", "Unexpected_Handler"}
        return sorted(taken - vectors)

    def frame(self, name):
        return self.frames.get(name, self.prologue.get(name, 0))

    def callees(self, name):
        out = set(self.edges.get(name, ()))
        if name in self.indirect_callers:
            out.update(self.address_taken)
        return out

    def reachable(self, roots):
        seen, todo = set(), list(roots)
        while todo:
            n = todo.pop()
            if n in seen:
                continue
            seen.add(n)
            todo.extend(self.callees(n))
        return seen

    def deepest(self, root):
        """(bytes, path) of the deepest call chain from root; cycles are reported, not followed."""
        memo, cycles = {}, []

        def visit(n, stack):
            if n in memo:
                return memo[n]
            if n in stack:
                cycles.append(stack[stack.index(n):] + [n])
                return (0, [])
            stack.append(n)
            best = (0, [])
            for c in sorted(self.callees(n)):
                d = visit(c, stack)
                if d[0] > best[0]:
                    best = d
            stack.pop()
            memo[n] = (self.frame(n) + best[0], [n] + best[1])
            return memo[n]

        sys.setrecursionlimit(100000)
        depth, path = visit(root, [])
        return depth, path, cycles


CONDITIONS = {"eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc", "hi", "ls", "ge", "lt", "gt", "le", "al"}


def count_registers(operands):
    regs = operands[operands.index("{") + 1: operands.index("}")]
    n = 0
    for part in regs.split(","):
        part = part.strip()
        if "-" in part:
            a, b = (int(re.sub(r"\D", "", x)) for x in part.split("-"))
            n += b - a + 1
        elif part:
            n += 1
    return n


def count_fp_bytes(operands):
    regs = operands[operands.index("{") + 1: operands.index("}")]
    width = 8 if "d" in regs else 4
    return count_registers("{" + regs + "}") * width


def demangle(names, tool):
    if not names:
        return {}
    out = subprocess.run([tool], input="\n".join(names), capture_output=True, text=True, check=True).stdout
    return dict(zip(names, out.splitlines()))


def check(img, args):
    errors = []
    for name in sorted(img.functions):
        owner = img.owner(name)
        why = "; ".join(img.pulled_in_by(owner))
        if name in HEAP_SYMBOLS or NEW_RE.match(name):
            errors.append(f"heap: {name} is linked ({owner}; {why})")
        elif name in EXCEPTION_SYMBOLS:
            errors.append(f"exceptions: {name} is linked ({owner}; {why})")
        elif DELETE_RE.match(name) and "hal/mps2" not in owner:
            errors.append(f"heap: {name} comes from {owner}, not the board's trapping definition")
    soft = soft_double_hot_path(img, args.estimator_lib)
    for fn, helper in soft:
        errors.append(f"soft-double in the estimator hot path: {fn} calls {helper}")
    if errors:
        names = sorted({e.split(": ", 1)[1].split(" ")[0] for e in errors})
        pretty = demangle(names, args.cxxfilt)
        sys.stderr.write("image_analysis: uwbnav_mps2.elf violates the firmware rules:\n")
        for e in errors:
            kind, rest = e.split(": ", 1)
            first = rest.split(" ")[0]
            sys.stderr.write(f"  {kind}: {pretty.get(first, first)}{rest[len(first):]}\n")
        return 1
    print(f"image_analysis: no heap, no exceptions, no soft-double in the estimator hot path "
          f"({len(estimator_hot_path(img, args.estimator_lib))} estimator functions)")
    return 0


def estimator_hot_path(img, estimator_lib):
    """Estimator functions the per-sample entry points reach."""
    lib = os.path.basename(estimator_lib)
    roots = [n for n in img.functions if n.startswith(ESTIMATOR_ROOTS)]
    return sorted(n for n in img.reachable(roots) if lib in img.owner(n))


def soft_double_hot_path(img, estimator_lib):
    """(estimator hot-path function, soft-double symbol it reaches directly or via library code)."""
    estimator_hot = estimator_hot_path(img, estimator_lib)
    found = []
    for fn in estimator_hot:
        # Follow calls into code that is not ours (libm, libgcc) to catch doubles inside.
        seen, todo = set(), [fn]
        while todo:
            n = todo.pop()
            if n in seen:
                continue
            seen.add(n)
            for c in img.callees(n):
                if is_soft_double(c):
                    found.append((fn if n == fn else f"{fn} (via {n})", c))
                elif c not in seen and "uwbnav" not in img.owner(c) and "hal/mps2" not in img.owner(c):
                    todo.append(c)
    return sorted(set(found))


def sections(elf, size_tool):
    out = {}
    for line in run([size_tool, "-A", elf]).splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0].startswith(".") and parts[1].isdigit():
            out[parts[0]] = int(parts[1])
    return out


def footprint(img, args):
    sec = sections(args.elf, args.size)
    flash = sec.get(".text", 0) + sec.get(".data", 0) + sec.get(".tdata", 0)
    ram_static = sum(sec.get(s, 0) for s in (".data", ".tdata", ".tbss", ".bss"))
    objects = sorted(((size, name) for name, (_, size) in img.objects.items() if size > 0), reverse=True)
    top_objects = [(name, size, img.owner(name)) for size, name in objects[:12]]
    depth, path, cycles = img.deepest(ENTRY)
    tick_depth, tick_path, _ = img.deepest(HOT_ROOT)
    init_depth, _, _ = img.deepest(INIT_ROOT)
    fault_depth, _, _ = img.deepest("Fault_Handler")
    lib = os.path.basename(args.estimator_lib)
    hot = img.reachable([HOT_ROOT])
    estimator_hot = set(estimator_hot_path(img, args.estimator_lib))
    soft_hot = soft_double_hot_path(img, args.estimator_lib)
    soft_cold = sorted({(n, c) for n in img.functions if lib in img.owner(n) and n not in estimator_hot
                        for c in img.callees(n) if is_soft_double(c)})
    soft_fw_hot = sorted({(n, c) for n in hot if "libuwbnav_firmware" in img.owner(n)
                          for c in img.callees(n) if is_soft_double(c)})
    names = {n for n, _ in soft_hot + soft_cold + soft_fw_hot} | set(path) | set(tick_path)
    names |= {n for n, _, _ in top_objects}
    names = sorted(n.split(" ")[0] for n in names)
    pretty = demangle(names, args.cxxfilt)
    from_prologue = [n for n in img.reachable([ENTRY]) if n not in img.frames]
    result = {
        "sections": sec,
        "flash_firmware_bytes": flash,
        "flash_replay_data_bytes": sec.get(".replay_data", 0),
        "ram_static_bytes": ram_static,
        "stack_reserved_bytes": sec.get(".stack", 0),
        "stack_worst_bytes": depth + EXCEPTION_FRAME_BYTES + fault_depth,
        "stack_main_path_bytes": depth,
        "stack_exception_bytes": EXCEPTION_FRAME_BYTES + fault_depth,
        "stack_tick_bytes": tick_depth,
        "stack_init_bytes": init_depth,
        "stack_path": [(pretty.get(n, n), img.frame(n)) for n in path],
        "stack_cycles": [[pretty.get(n, n) for n in c] for c in cycles],
        "stack_dynamic_functions": sorted(pretty.get(n, n) for n in img.dynamic_sp),
        "stack_frames_from_prologue": len(from_prologue),
        "stack_frames_from_gcc": len(img.reachable([ENTRY])) - len(from_prologue),
        "indirect_call_targets": len(img.address_taken),
        "ram_objects": [(pretty.get(n, n), s, os.path.basename(o)) for n, s, o in top_objects],
        "tick_functions": len(hot),
        "estimator_hot_functions": len(estimator_hot),
        "soft_double_estimator_hot": [(pretty.get(n.split(" ")[0], n), c) for n, c in soft_hot],
        "soft_double_estimator_other": [(pretty.get(n, n), c) for n, c in soft_cold],
        "soft_double_firmware_hot": [(pretty.get(n, n), c) for n, c in soft_fw_hot],
    }
    json.dump(result, sys.stdout, indent=1)
    sys.stdout.write("\n")
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("command", choices=["check", "footprint"])
    p.add_argument("--elf", required=True)
    p.add_argument("--map", required=True)
    p.add_argument("--estimator-lib", required=True, help="libuwbnav_estimator.a (ownership of estimator code)")
    p.add_argument("--callgraph-dir", required=True, help="build tree holding the .ci files")
    p.add_argument("--nm", default="arm-none-eabi-nm")
    p.add_argument("--objdump", default="arm-none-eabi-objdump")
    p.add_argument("--size", default="arm-none-eabi-size")
    p.add_argument("--cxxfilt", default="arm-none-eabi-c++filt")
    args = p.parse_args()
    img = Image(args)
    return check(img, args) if args.command == "check" else footprint(img, args)


if __name__ == "__main__":
    sys.exit(main())
