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
             largest RAM objects, the worst-case stack, soft-double use and,
             with --profile, the flat profile of the profile image) for
             scripts/footprint.sh.

Method (docs/footprint.md): the call graph comes from the disassembly of the
linked image (bl/blx/b.w to symbols; blx/bx to a register is an indirect call,
resolved conservatively to every address-taken function); frame sizes come from
GCC's -fcallgraph-info=su (.ci files) for code compiled here and from the
prologue (push/vpush/sub sp) for library code. The stack bound is the deepest
path plus one exception frame with FPU context stacked by a fault at that
point (the fault handler itself restarts on a fresh stack).
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
RAM_BASE = 0x20000000
NOT_ALLOCATED = (".debug", ".comment", ".ARM.attributes", ".stab")
HOT_ROOT = "_ZN6uwbnav3App4tickEy"
# The estimator's per-sample entry points (mangled-name prefixes; clones included).
ESTIMATOR_ROOTS = ("_ZN6uwbnav9Navigator6on_imu", "_ZN6uwbnav9Navigator8on_range", "_ZN6uwbnav9Navigator6output")
INIT_ROOT = "_ZN6uwbnav3App4initEv"
ENTRY = "Reset_Handler"
# Exception entry: 8 words basic frame + 18 words FP context (S0-S15, FPSCR, reserved).
EXCEPTION_FRAME_BYTES = 104


def run(cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def is_soft_double_name(name):
    return bool(SOFT_DOUBLE_RE.match(name)) or name in DOUBLE_LIBM


class Image:
    def __init__(self, args):
        self.elf = args.elf
        self.readelf = args.readelf
        self.objdump = args.objdump
        self.functions = {}   # name -> (addr, size)
        self.aliases = {}     # addr -> every function name at that address
        self.objects = {}     # name -> (addr, size) data objects
        self.markers = {}     # name -> addr of linker-script symbols (NOTYPE)
        self._read_symbols()
        self.sections = self._read_sections()
        self.owner_ranges = self._read_map(args.map)
        self._starts = [r[0] for r in self.owner_ranges]
        self.members = self._read_archive_members(args.map)
        self.frames, self.frame_kind = self._read_frames(args.callgraph_dir)
        self.edges, self.indirect_sites, self.dynamic_sp = self._read_disassembly()
        self.address_taken = self._resolve_indirect()

    def _read_sections(self):
        out = []
        for line in run([self.readelf, "-SW", self.elf]).splitlines():
            m = re.match(r"^\s*\[\s*\d+\]\s+(\S+)\s+\S+\s+([0-9a-f]{8})\s+[0-9a-f]+\s+([0-9a-f]+)", line)
            if m:
                out.append((m.group(1), int(m.group(2), 16), int(m.group(3), 16)))
        return out

    def _read_symbols(self):
        """Functions and data objects from the ELF symbol table (readelf: FUNC / OBJECT)."""
        for line in run([self.readelf, "-sW", self.elf]).splitlines():
            parts = line.split()
            if len(parts) != 8 or not parts[0][:-1].isdigit() or parts[6] == "UND":
                continue
            addr, size, kind, name = int(parts[1], 16), int(parts[2], 0), parts[3], parts[7]
            if kind == "FUNC":
                addr &= ~1
                self.functions.setdefault(name, (addr, size))
                self.aliases.setdefault(addr, set()).add(name)
            elif kind == "OBJECT":
                self.objects[name] = (addr, size)
            elif kind == "NOTYPE":
                self.markers[name] = addr

    def section_of(self, addr):
        for name, start, size in self.sections:
            if start <= addr < start + size:
                return name
        return ""

    def canonical(self, name):
        """One name per address (aliases such as malloc/__malloc_malloc collapse)."""
        if name not in self.functions:
            return name
        return min(self.aliases[self.functions[name][0]])

    def names_of(self, name):
        if name not in self.functions:
            return {name}
        return self.aliases[self.functions[name][0]]

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
                    name = m.group(1) or pending
                    start, size = int(m.group(2), 16), int(m.group(3), 16)
                    allocated = not name.startswith(NOT_ALLOCATED)
                    if size > 0 and allocated and not m.group(4).startswith("load address"):
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
        """Direct call edges, indirect call sites, frame sizes from prologues, dynamic sp users."""
        edges = {}
        sites = {}     # function -> list of (slot offset or None, loaded through a vptr)
        dynamic = set()
        prologue = {}
        loads = {}     # register -> (base register, offset, base loaded from offset 0)
        current = None
        head_re = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
        insn_re = re.compile(r"^\s+[0-9a-f]+:\s+(\S+)\s*(.*)$")
        target_re = re.compile(r"<([^>+]+)(\+0x[0-9a-f]+)?>")
        ldr_re = re.compile(r"^(r\d+|ip|lr|sl|fp),\s*\[(r\d+|ip|lr|sl|fp|sp)(?:,\s*#(-?\d+))?\]$")
        reg_re = re.compile(r"^(r\d+|ip|sl|fp)$")
        out = run([self.objdump, "-d", "--no-show-raw-insn", self.elf])
        for line in out.splitlines():
            h = head_re.match(line)
            if h:
                current = self.canonical(h.group(2))
                edges.setdefault(current, set())
                prologue.setdefault(current, 0)
                loads = {}
                continue
            m = insn_re.match(line)
            if not m or current is None:
                continue
            op, operands = m.group(1), m.group(2).split(";")[0].split("@")[0].strip()
            base = op.split(".")[0]
            if base in ("bl", "blx", "b", "bx") or (base.startswith("b") and base[1:] in CONDITIONS):
                t = target_re.search(operands)
                target = self.canonical(t.group(1)) if t else None
                if t and not t.group(2) and target != current and target in self.functions:
                    edges[current].add(target)
                elif base in ("blx", "bx") and reg_re.match(operands):
                    src = loads.get(operands)
                    sites.setdefault(current, []).append((src[1], src[2]) if src else (None, False))
                continue
            if base in ("push", "stmdb", "stmfd") and (base == "push" or operands.startswith("sp!")):
                prologue[current] += 4 * count_registers(operands)
            elif base in ("vpush", "vstmdb") and (base == "vpush" or operands.startswith("sp!")):
                prologue[current] += count_fp_bytes(operands)
            elif base in ("sub", "subw") and re.match(r"^sp,\s*(sp,\s*)?#", operands):
                prologue[current] += int(operands.split("#")[1].split()[0], 0)
            elif base in ("sub", "subw") and re.match(r"^sp,\s*(sp,\s*)?r", operands):
                dynamic.add(current)
            # Register tracking for indirect calls: which load produced the call target.
            dest = operands.split(",")[0].strip()
            lm = ldr_re.match(operands) if base == "ldr" else None
            if lm:
                b = loads.get(lm.group(2))
                through_vptr = b is not None and b[1] == 0
                loads[lm.group(1)] = (lm.group(2), int(lm.group(3) or 0), through_vptr)
            elif base not in NON_WRITING and dest in loads:
                del loads[dest]
        self.prologue = prologue
        return edges, sites, dynamic

    def _words(self):
        """addr -> 32-bit word of every allocated PROGBITS section."""
        with open(self.elf, "rb") as f:
            data = f.read()
        shoff, = struct.unpack_from("<I", data, 0x20)
        shentsize, shnum = struct.unpack_from("<HH", data, 0x2E)
        words = {}
        for i in range(shnum):
            _, sh_type, flags, addr, offset, size = struct.unpack_from("<IIIIII", data, shoff + i * shentsize)
            if sh_type != 1 or not flags & 2:  # PROGBITS, ALLOC
                continue
            for k in range(0, size - 3, 4):
                words[addr + k], = struct.unpack_from("<I", data, offset + k)
        return words

    def _resolve_indirect(self):
        """Candidate targets of indirect calls: vtable slots, init_array, other address-taken functions."""
        words = self._words()
        thumb = {addr | 1: min(names) for addr, names in self.aliases.items()}
        vtable_slots, in_vtables = {}, set()
        for name, (addr, size) in self.objects.items():
            if not name.startswith("_ZTV"):
                continue
            for k in range(8, size, 4):  # skip offset-to-top and typeinfo: the vptr points at slot 0
                fn = thumb.get(words.get(addr + k))
                if fn:
                    vtable_slots.setdefault(k - 8, set()).add(fn)
                    in_vtables.add(fn)
        init = set()
        lo, hi = self.markers.get("__init_array_start"), self.markers.get("__init_array_end")
        if lo is not None and hi is not None:
            init = {thumb[words[a]] for a in range(lo, hi, 4) if words.get(a) in thumb}
        # Exception handlers (the vector table) and main are entered by the hardware and
        # the reset code only; a data word that happens to equal their address is no call.
        vectors = {"main"}
        for name, (a, size) in self.objects.items():
            if "kVectors" in name:
                vectors |= {thumb[words[x]] for x in range(a, a + size, 4) if words.get(x) in thumb}
        taken = {thumb[w] for w in words.values() if w in thumb}
        others = taken - in_vtables - init - vectors
        self.vtable_slots = vtable_slots
        self.vtable_functions = in_vtables
        self.init_functions = init
        self.pointer_targets_lib = {f for f in others if self.is_library(f)}
        self.pointer_targets_ours = others - self.pointer_targets_lib
        return sorted(taken - vectors)

    def is_library(self, name):
        return "/usr/lib/" in self.owner(name)

    def is_soft_double(self, name):
        return any(is_soft_double_name(n) for n in self.names_of(name))

    def frame(self, name):
        for n in self.names_of(name):
            if n in self.frames:
                return self.frames[n]
        return self.prologue.get(name, 0)

    def callees(self, name):
        """Direct callees plus the candidates of each indirect call site (docs/footprint.md):
        Reset_Handler -> static constructors; library code -> library functions whose address
        is taken; a call through a vtable slot -> that slot of every vtable; any other call
        in our code -> our non-virtual address-taken functions (and every virtual function
        when the target's origin is unknown)."""
        out = set(self.edges.get(name, ()))
        for off, through_vptr in self.indirect_sites.get(name, ()):
            if name == ENTRY:
                out |= self.init_functions
            elif self.is_library(name):
                out |= self.pointer_targets_lib
            elif through_vptr and off in self.vtable_slots:
                out |= self.vtable_slots[off]
            elif off is None:
                out |= self.pointer_targets_ours | self.vtable_functions
            else:
                out |= self.pointer_targets_ours
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


# Instructions whose first operand is not a destination register.
NON_WRITING = {"str", "strb", "strh", "strd", "cmp", "cmn", "tst", "teq", "push", "pop", "stm", "stmia", "stmdb",
               "vstr", "vpush", "vstmia", "vstmdb", "it", "ite", "itt", "itte", "ittt", "nop", "dmb", "dsb", "isb"}
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
        canonical = img.canonical(name)
        why = "; ".join(img.pulled_in_by(owner))
        # One caller per object file that calls it (the objects to fix), ours first.
        by_object = {}
        for f in sorted(f for f, cs in img.edges.items() if canonical in cs):
            by_object.setdefault(img.owner(f), f)
        callers = [by_object[o] for o in sorted(by_object, key=lambda o: ("/usr/lib/" in o, o))]
        if callers:
            why += "; called by " + ", ".join(callers[:5]) + (" ..." if len(callers) > 5 else "")
        if name in HEAP_SYMBOLS or NEW_RE.match(name):
            errors.append(f"heap: {name} is linked ({owner}; {why})")
        elif name in EXCEPTION_SYMBOLS:
            errors.append(f"exceptions: {name} is linked ({owner}; {why})")
        elif DELETE_RE.match(name) and "hal/mps2" not in owner:
            errors.append(f"heap: {name} comes from {owner}, not the board's trapping definition")
    soft = soft_double_hot_path(img, args.estimator_lib, args.roots)
    for fn, helper in soft:
        errors.append(f"soft-double in the estimator hot path: {fn} calls {helper}")
    if errors:
        mangled = sorted({w.strip(",;()") for e in errors for w in e.split() if w.startswith("_Z")})
        pretty = demangle(mangled, args.cxxfilt)
        sys.stderr.write(f"image_analysis: {os.path.basename(args.elf)} violates the firmware rules:\n")
        for e in errors:
            for m in mangled:
                e = e.replace(m, pretty.get(m, m))
            sys.stderr.write(f"  {e}\n")
        return 1
    print(f"image_analysis: no heap, no exceptions, no soft-double in the estimator hot path "
          f"({len(estimator_hot_path(img, args.estimator_lib, args.roots))} estimator functions)")
    return 0


def estimator_hot_path(img, estimator_lib, root_prefixes=ESTIMATOR_ROOTS):
    """Estimator functions the per-sample entry points reach."""
    lib = os.path.basename(estimator_lib)
    roots = [n for n in img.functions if n.startswith(tuple(root_prefixes))]
    return sorted(n for n in img.reachable(roots) if lib in img.owner(n))


def soft_double_hot_path(img, estimator_lib, root_prefixes=ESTIMATOR_ROOTS):
    """(estimator hot-path function, soft-double symbol it reaches directly or via library code)."""
    estimator_hot = estimator_hot_path(img, estimator_lib, root_prefixes)
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
                if img.is_soft_double(c):
                    found.append((fn if n == fn else f"{fn} (via {n})", c))
                elif c not in seen and "uwbnav" not in img.owner(c) and "hal/mps2" not in img.owner(c):
                    todo.append(c)
    return sorted(set(found))


def component(img, name):
    """Coarse owner of a function for the profile: where the instructions go."""
    owner = img.owner(name)
    if img.is_soft_double(name):
        return "soft-double helpers and double libm (libgcc, picolibc)"
    if "libuwbnav_estimator" in owner:
        return "estimator (estimator/)"
    if "libuwbnav_firmware" in owner:
        return "firmware (firmware/: App, validation, CAN, console)"
    if "hal/mps2" in owner:
        return "MPS2 board and harness (hal/mps2/)"
    if "libm_" in owner:
        return "float libm (picolibc)"
    if "libgcc" in owner:
        return "libgcc integer/float helpers"
    return "picolibc (string, stdio, other)"


def path_component(path):
    """Coarse owner of an input file for the flash breakdown."""
    for key, label in (("libuwbnav_estimator", "estimator (estimator/)"),
                       ("libuwbnav_firmware", "firmware (firmware/)"),
                       ("hal/mps2", "MPS2 board and harness (hal/mps2/)"),
                       ("libm_", "picolibc libm"),
                       ("tinystdio", "picolibc stdio (integer-only snprintf)"),
                       ("libgcc", "libgcc (64-bit integer and conversion helpers)"),
                       ("libstdc++", "libstdc++/libsupc++"),
                       ("libsupc++", "libstdc++/libsupc++")):
        if key in path:
            return label
    return "picolibc (other)"


def flash_breakdown(img):
    replay = next((start for name, start, _ in img.sections if name == ".replay_data"), RAM_BASE)
    out = {}
    for start, end, path in img.owner_ranges:
        if start < replay:
            c = path_component(path)
            out[c] = out.get(c, 0) + end - start
    return sorted(out.items(), key=lambda kv: -kv[1])


def profile(img, digest_path):
    """Flat profile from the profile image's sampled (PC, LR) pairs: per function, per
    component, and for library functions the callers (the function holding the LR:
    right for leaf functions that keep LR, such as memset; meaningless where LR is
    reused as a scratch register)."""
    starts = sorted((addr, size, min(names)) for addr, names in img.aliases.items()
                    for size in [max(img.functions[n][1] for n in names)])
    keys = [s[0] for s in starts]

    def function_at(addr):
        addr &= ~1
        i = bisect.bisect_right(keys, addr) - 1
        if i < 0:
            return "(unknown)"
        # Assembly helpers (libgcc) carry size 0: they extend to the next symbol.
        end = starts[i][0] + starts[i][1] if starts[i][1] else (keys[i + 1] if i + 1 < len(keys) else addr + 1)
        return starts[i][2] if addr < end else "(unknown)"

    per_fn, callers, total, period = {}, {}, 0, 0
    with open(digest_path) as f:
        for line in f:
            if line.startswith("profile samples="):
                period = int(line.split("period_ticks=")[1])
            elif line.startswith("profile pc="):
                fields = dict(x.split("=") for x in line.split()[1:])
                n = int(fields["n"])
                name = function_at(int(fields["pc"]))
                per_fn[name] = per_fn.get(name, 0) + n
                total += n
                if name in img.functions and img.is_library(name):
                    caller = function_at(int(fields["lr"]))
                    if caller != name:
                        callers.setdefault(name, {})
                        callers[name][caller] = callers[name].get(caller, 0) + n
    comps = {}
    for name, n in per_fn.items():
        c = component(img, name) if name in img.functions else "(unknown)"
        comps[c] = comps.get(c, 0) + n
    top = sorted(per_fn.items(), key=lambda kv: -kv[1])[:20]
    top_callers = {name: sorted(callers.get(name, {}).items(), key=lambda kv: -kv[1])[:3] for name, _ in top}
    return total, period, top, sorted(comps.items(), key=lambda kv: -kv[1]), top_callers


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
    ram = sorted(((size, name) for name, (a, size) in img.objects.items() if size > 0 and a >= RAM_BASE),
                 reverse=True)
    top_objects = [(name, size, img.owner(name)) for size, name in ram[:10]]
    rom = sorted(((size, name) for name, (a, size) in img.objects.items()
                  if size > 0 and a < RAM_BASE and "replay_data" not in img.section_of(a)), reverse=True)
    top_rom = [(name, size, img.owner(name)) for size, name in rom[:8]]
    depth, path, cycles = img.deepest(ENTRY)
    tick_depth, tick_path, _ = img.deepest(HOT_ROOT)
    init_depth, _, _ = img.deepest(INIT_ROOT)
    fault_depth, _, _ = img.deepest("Fault_Handler")
    lib = os.path.basename(args.estimator_lib)
    hot = img.reachable([HOT_ROOT])
    estimator_hot = set(estimator_hot_path(img, args.estimator_lib))
    soft_hot = soft_double_hot_path(img, args.estimator_lib)
    soft_cold = sorted({(n, c) for n in img.functions if lib in img.owner(n) and n not in estimator_hot
                        for c in img.callees(n) if img.is_soft_double(c)})
    soft_fw_hot = sorted({(n, c) for n in hot if "libuwbnav_firmware" in img.owner(n)
                          for c in img.callees(n) if img.is_soft_double(c)})
    names = {n for n, _ in soft_hot + soft_cold + soft_fw_hot} | set(path) | set(tick_path)
    names |= {n for n, _, _ in top_objects + top_rom}
    names = sorted(n.split(" ")[0] for n in names)
    pretty = demangle(names, args.cxxfilt)
    from_prologue = [n for n in img.reachable([ENTRY]) if n not in img.frames]
    result = {
        "sections": sec,
        "flash_firmware_bytes": flash,
        "flash_replay_data_bytes": sec.get(".replay_data", 0),
        "flash_by_component": flash_breakdown(img),
        "ram_static_bytes": ram_static,
        "stack_reserved_bytes": sec.get(".stack", 0),
        "stack_worst_bytes": depth + EXCEPTION_FRAME_BYTES,
        "stack_main_path_bytes": depth,
        "stack_exception_bytes": EXCEPTION_FRAME_BYTES,
        "stack_fault_handler_bytes": fault_depth,
        "stack_tick_bytes": tick_depth,
        "stack_init_bytes": init_depth,
        "stack_path": [(pretty.get(n, n), img.frame(n)) for n in path],
        "stack_cycles": [[pretty.get(n, n) for n in c] for c in cycles],
        "stack_dynamic_functions": sorted(pretty.get(n, n) for n in img.dynamic_sp),
        "stack_frames_from_prologue": len(from_prologue),
        "stack_frames_from_gcc": len(img.reachable([ENTRY])) - len(from_prologue),
        "indirect_call_sites": sum(len(v) for v in img.indirect_sites.values()),
        "ram_objects": [(pretty.get(n, n), s, os.path.basename(o)) for n, s, o in top_objects],
        "flash_objects": [(pretty.get(n, n), s, os.path.basename(o)) for n, s, o in top_rom],
        "tick_functions": len(hot),
        "estimator_hot_functions": len(estimator_hot),
        "soft_double_estimator_hot": [(pretty.get(n.split(" ")[0], n), c) for n, c in soft_hot],
        "soft_double_estimator_other": [(pretty.get(n, n), c) for n, c in soft_cold],
        "soft_double_firmware_hot": [(pretty.get(n, n), c) for n, c in soft_fw_hot],
    }
    if args.profile:
        total, period, top, comps, top_callers = profile(img, args.profile)
        names = {n for n, _ in top} | {c for cs in top_callers.values() for c, _ in cs}
        pretty.update(demangle(sorted(names), args.cxxfilt))
        result["profile_samples"] = total
        result["profile_period_ticks"] = period
        result["profile_functions"] = [
            (pretty.get(n, n), c, os.path.basename(img.owner(n)),
             [(pretty.get(k, k), m) for k, m in top_callers.get(n, [])]) for n, c in top]
        result["profile_components"] = comps
    json.dump(result, sys.stdout, indent=1)
    sys.stdout.write("\n")
    return 0


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("command", choices=["check", "footprint"])
    p.add_argument("--elf", required=True)
    p.add_argument("--map", required=True)
    p.add_argument("--estimator-lib", required=True, help="libuwbnav_estimator.a (ownership of estimator code)")
    p.add_argument("--roots", nargs="+", default=list(ESTIMATOR_ROOTS),
                   help="mangled-name prefixes of the hot-path entry points (default: Navigator on_imu/on_range/output)")
    p.add_argument("--callgraph-dir", required=True, help="build tree holding the .ci files")
    p.add_argument("--readelf", default="arm-none-eabi-readelf")
    p.add_argument("--objdump", default="arm-none-eabi-objdump")
    p.add_argument("--size", default="arm-none-eabi-size")
    p.add_argument("--cxxfilt", default="arm-none-eabi-c++filt")
    p.add_argument("--profile", help="footprint: digest of the profile image (sampled PCs)")
    args = p.parse_args()
    img = Image(args)
    return check(img, args) if args.command == "check" else footprint(img, args)


if __name__ == "__main__":
    sys.exit(main())
