# SPDX-License-Identifier: Apache-2.0
"""Reads a linked ARMv6-M firmware image for the build-time checks
(tools/check/image-check) and the footprint table (tools/check/footprint): functions
with their object file, frame size and call edges, taken from the ELF
(nm, objdump -d), the linker map and GCC's -fstack-usage (.su) files.

Why the disassembly and not the source: what the checks guard (a function
running from flash, a stack frame, a libgcc helper) only exists after the
compiler and linker have chosen inlining, clones and placement."""
import fnmatch
import re
import subprocess
from pathlib import Path

TOOLS = {"readelf": "arm-none-eabi-readelf", "objdump": "arm-none-eabi-objdump", "objcopy": "arm-none-eabi-objcopy",
         "addr2line": "arm-none-eabi-addr2line"}

# objdump -d lines: "<addr> <name>:" opens a function, then instructions.
_FUNC_RE = re.compile(r"^([0-9a-f]+) <([^>]+)>:$")
_INSN_RE = re.compile(r"^\s+([0-9a-f]+):\s+((?:[0-9a-f]{4,8} ?)+)\s+(\S+)\s*(.*)$")
_TARGET_RE = re.compile(r"^([0-9a-f]+)\s+<([^>+]+)(\+0x[0-9a-f]+)?>")
_LIT_RE = re.compile(r"[;@]\s*\(([0-9a-f]+) <")
# A map's input-section line: " .text.name  0xADDR  0xSIZE  object", the
# name on its own line when it is long.
_MAP_SEC_RE = re.compile(r"^ (\.[^\s]+|COMMON)?\s*0x([0-9a-f]+)[ \t]+0x([0-9a-f]+)[ \t]+(\S.*)$", re.M)


# Suffixes GCC gives a clone or an LTO-local copy of a function.
CLONE_SUFFIX = r"(\.(isra|constprop|part|cold|lto_priv)(\.\d+)?)+$"


def is_lto_partition(obj):
    """True for a link-time-optimisation partition object (ccXXXX.ltrans0.ltrans.o)."""
    return ".ltrans" in obj


def run(tool, *args):
    return subprocess.run([TOOLS[tool], *args], check=True, capture_output=True, text=True).stdout


class Insn:
    __slots__ = ("addr", "size", "op", "args", "target", "lit")

    def __init__(self, addr, size, op, args):
        self.addr, self.size, self.op, self.args = addr, size, op, args
        self.target = None  # branch/call destination address
        self.lit = None     # address of a pc-relative literal load
        m = _TARGET_RE.match(args)
        if m and (op.startswith("b") and op not in ("bic", "bics", "bkpt")):
            self.target = int(m.group(1), 16)
        m = _LIT_RE.search(args)
        if m and op.startswith("ldr"):
            self.lit = int(m.group(1), 16)


class Func:
    def __init__(self, name, addr, size):
        self.names = [name]
        self.addr, self.size = addr, size
        self.obj = None          # "archive(member)" or object path, from the map
        self.src = None          # source file name of an LTO partition's function (debug info)
        self.insns = []
        self.words = {}          # address -> 32-bit literal word inside the function
        self.frame = None        # bytes, from .su or the prologue
        self.frame_src = None
        self.calls = set()       # direct callee addresses (bl, or a branch leaving the function)
        self.indirect = []       # Insn of each blx/bx rN that is not a return

    @property
    def name(self):
        return self.names[0]

    def label(self):
        if self.obj and is_lto_partition(self.obj):
            return f"{self.name} [{self.src or '?'}, LTO]"
        obj = self.obj.split("(")[-1].rstrip(")") if self.obj else "?"
        return f"{self.name} [{Path(obj).name}]"


class Image:
    """Functions of one linked image, keyed by start address (Thumb bit off)."""

    def __init__(self, elf, map_path=None, su_root=None):
        self.elf = Path(elf)
        self.map_path = Path(map_path) if map_path else self.elf.with_suffix(".map")
        self.funcs = {}
        self.symbols = {}   # name -> address, every defined symbol
        self.symbol_sizes = {}  # name -> st_size of that symbol
        self.sections = []  # (addr, size, obj, section name) of every map input section
        self._read_symbols()
        self._read_map()
        self._read_disassembly()
        self._read_frames(Path(su_root) if su_root else None)

    # ---- symbols and map ----
    def _read_symbols(self):
        for line in run("readelf", "-s", "-W", str(self.elf)).splitlines():
            parts = line.split()
            if len(parts) != 8 or not parts[0].endswith(":") or parts[6] == "UND" or parts[1] == "Value":
                continue
            addr, size, kind, bind, name = int(parts[1], 16), int(parts[2], 0), parts[3], parts[4], parts[7]
            self.symbols.setdefault(name, addr)
            self.symbol_sizes.setdefault(name, size)
            if kind != "FUNC":
                continue
            a = addr & ~1
            if a in self.funcs:
                f = self.funcs[a]
                # A strong global name first: a weak alias is the lesser name.
                if bind == "GLOBAL":
                    f.names.insert(0, name)
                else:
                    f.names.append(name)
                f.size = max(f.size, size)
            else:
                self.funcs[a] = Func(name, a, size)

    def _read_map(self):
        text = self.map_path.read_text(errors="replace")
        # Only the part after "Linker script and memory map" places sections.
        start = text.find("Linker script and memory map")
        text = text[start:] if start >= 0 else text
        for m in _MAP_SEC_RE.finditer(text):
            name, addr, size, obj = m.group(1), int(m.group(2), 16), int(m.group(3), 16), m.group(4).strip()
            if size == 0 or obj.startswith("0x") or " " in obj:
                continue
            self.sections.append((addr, size, obj, name or ""))
        for f in self.funcs.values():
            for addr, size, obj, _ in self.sections:
                if addr <= f.addr < addr + size:
                    f.obj = obj
                    break
        self._read_lto_sources()

    def _read_lto_sources(self):
        """A function of an LTO partition gets its source file from the debug
        line table (the outermost function at its entry), so that a config
        name "fn@file.c.obj" still tells two statics of the same name apart.
        Without debug information the name alone is matched."""
        lto = [f for f in self.funcs.values() if f.obj and is_lto_partition(f.obj)]
        if not lto:
            return
        out = run("addr2line", "-a", "-f", "-i", "-e", str(self.elf), *[hex(f.addr) for f in lto])
        last = {}
        cur = None
        lines = out.splitlines()
        k = 0
        while k < len(lines):
            if re.match(r"^0x[0-9a-f]+$", lines[k]):
                cur = int(lines[k], 16)
                k += 1
                continue
            if cur is not None and k + 1 < len(lines):
                last[cur] = lines[k + 1].split(":")[0]
            k += 2
        for f in lto:
            src = last.get(f.addr, "??")
            f.src = None if src.startswith("??") else Path(src).name

    # ---- code ----
    def _read_disassembly(self):
        cur = None
        for line in run("objdump", "-d", "--no-show-raw-insn", str(self.elf)).splitlines():
            m = _FUNC_RE.match(line)
            if m:
                addr = int(m.group(1), 16)
                cur = self.funcs.get(addr)
                continue
            if cur is None:
                continue
            m = re.match(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$", line)
            if not m:
                continue
            addr, op, args = int(m.group(1), 16), m.group(2), m.group(3)
            if not (cur.addr <= addr < cur.addr + max(cur.size, 2)):
                continue
            if op == ".word":
                cur.words[addr] = int(args.split()[0], 16)
                continue
            if op.startswith("."):
                continue
            cur.insns.append(Insn(addr, 2, op, args))
        # Literal words also come from raw bytes: objdump shows some as code.
        for f in self.funcs.values():
            for i in f.insns:
                if i.lit is not None and i.lit not in f.words:
                    f.words[i.lit] = None
            self._edges(f)
        self._fill_literals()

    def _fill_literals(self):
        need = [(f, a) for f in self.funcs.values() for a, v in f.words.items() if v is None]
        if not need:
            return
        data = self.read_words(sorted({a for _, a in need}))
        for f, a in need:
            f.words[a] = data.get(a)

    def _memory(self):
        """Bytes of every loaded section by address (objdump -s), cached."""
        if hasattr(self, "_mem"):
            return self._mem
        mem = {}
        keep = False
        for line in run("objdump", "-s", str(self.elf)).splitlines():
            if line.startswith("Contents of section "):
                # Only what the image loads: debug sections restart at address 0.
                sec = line[len("Contents of section "):].rstrip(":")
                keep = not sec.startswith((".debug", ".comment", ".ARM.attributes"))
                continue
            m = keep and re.match(r"^ ([0-9a-f]{4,8}) ((?:[0-9a-f]{2,8} ){1,4})", line)
            if m:
                base = int(m.group(1), 16)
                raw = bytes.fromhex(m.group(2).replace(" ", ""))
                for k, b in enumerate(raw):
                    mem[base + k] = b
        self._mem = mem
        return mem

    def read_words(self, addrs):
        """32-bit words of the image at the given addresses (VMA)."""
        mem = self._memory()
        out = {}
        for a in addrs:
            if all(a + k in mem for k in range(4)):
                out[a] = int.from_bytes(bytes(mem[a + k] for k in range(4)), "little")
        return out

    def loaded_words(self):
        """Every 4-aligned word the image loads, by address."""
        mem = self._memory()
        return self.read_words(a for a in mem if a % 4 == 0)

    def address_words(self):
        """Words the linker filled in with an absolute address (R_ARM_ABS32,
        kept in the ELF by --emit-relocs): exactly the stored addresses, no
        constant that merely looks like one. None if the image has no
        relocations (linked without --emit-relocs)."""
        out = run("readelf", "-r", "-W", str(self.elf))
        sites = set()
        debug = False  # relocations of .debug_* sections hold section offsets, not loaded addresses
        for line in out.splitlines():
            if line.startswith("Relocation section '"):
                debug = line.split("'")[1].startswith((".rel.debug", ".rela.debug"))
                continue
            parts = line.split()
            if not debug and len(parts) >= 3 and parts[2] == "R_ARM_ABS32":
                sites.add(int(parts[0], 16))
        if not sites:
            return None
        return self.read_words(sorted(sites))

    def _edges(self, f):
        # register -> ("lit", literal address) while it holds a literal
        # (the naked handlers' "ldr rX, =fn; bx rX").
        last_lit = {}
        for i in f.insns:
            if i.op == "bl" and i.target is not None and f.addr < i.target < f.addr + f.size:
                pass  # Thumb-1 far jump inside a function over 2 KiB (GCC saves LR for it): a branch
            elif i.op in ("bl", "blx") and i.target is not None:
                f.calls.add(i.target)
            elif i.op.startswith("b") and i.target is not None and not (f.addr <= i.target < f.addr + f.size):
                f.calls.add(i.target)  # a tail branch into another function
            elif i.op in ("blx", "bx") and i.args.strip() != "lr":
                reg = i.args.split()[0]
                if reg in last_lit:
                    f.calls.add(last_lit[reg])  # resolved in resolve_literal_calls
                else:
                    f.indirect.append(i)
            elif i.op == "mov" and i.args.replace(" ", "").startswith("pc,"):
                f.indirect.append(i)
            dest = i.args.split(",")[0].strip()
            src = i.args.split(",")[-1].strip()
            if i.lit is not None:
                last_lit[dest] = ("lit", i.lit)
            elif i.op == "mov" and src in last_lit:
                last_lit[dest] = last_lit[src]  # a linker veneer: "ldr r0, =fn; mov ip, r0"
            else:
                last_lit.pop(dest, None)

    def resolve_literal_calls(self):
        """bx/blx through a register loaded from a literal naming a function:
        a direct call in disguise (the naked fault and default handlers)."""
        for f in self.funcs.values():
            calls = set()
            for c in f.calls:
                if isinstance(c, tuple):
                    w = f.words.get(c[1])
                    if w is not None and (w & ~1) in self.funcs:
                        calls.add(w & ~1)
                    else:
                        f.indirect.append(Insn(c[1], 2, "bx", "r? (literal not a function)"))
                else:
                    g = self.func_at(c)
                    if g is None:
                        f.indirect.append(Insn(c, 2, "b", f"{c:#x} (no function there)"))
                    else:
                        calls.add(g.addr)  # itself too: a bl to its own entry is recursion
            f.calls = calls

    def func_at(self, addr):
        """The function whose body holds addr (a call may land on an inner
        entry point of a library routine)."""
        import bisect
        if not hasattr(self, "_starts"):
            self._starts = sorted(self.funcs)
        k = bisect.bisect_right(self._starts, addr) - 1
        if k < 0:
            return None
        f = self.funcs[self._starts[k]]
        return f if addr < f.addr + max(f.size, 2) else None

    # ---- frames ----
    def _read_frames(self, su_root):
        self.resolve_literal_calls()
        su = {}
        if su_root is not None:
            for p in su_root.rglob("*.su"):
                su[p.resolve()] = self._parse_su(p)
        for f in self.funcs.values():
            if f.obj and su:
                p = self._su_path(f.obj, self.elf.parent)
                table = su.get(p.resolve()) if p else None
                if table is not None:
                    base = re.sub(CLONE_SUFFIX, "", f.name)
                    for key in (f.name, re.sub(r"\.\d+$", "", f.name), base):
                        if key in table:
                            f.frame, f.frame_src = table[key], "su"
                            break
            if f.frame is None:
                f.frame, f.frame_src = self._prologue_frame(f), "prologue"

    @staticmethod
    def _parse_su(path):
        table = {}
        for line in path.read_text().splitlines():
            parts = line.split("\t")
            if len(parts) < 3:
                continue
            name = parts[0].rsplit(":", 1)[-1]
            size = int(parts[1])
            if parts[2].strip() not in ("static",):
                size = -size  # dynamic or bounded: flagged by the caller
            table[name] = max(table.get(name, size), size) if size >= 0 else size
        return table

    @staticmethod
    def _su_path(obj, link_dir):
        """Map entry -> .su file: "…/libkm_board.a(flash.c.obj)" is
        CMakeFiles/km_board.dir/…/flash.c.su; a plain object sits next to its .su."""
        m = re.match(r"^(.*/)?lib([^/]+)\.a\((.+)\)$", obj)
        if m:
            lib_dir, target, member = Path(m.group(1) or "."), m.group(2), m.group(3)
            if not lib_dir.is_absolute():
                lib_dir = link_dir / lib_dir
            cands = list((lib_dir / "CMakeFiles" / f"{target}.dir").rglob(Path(member).with_suffix(".su").name))
            return cands[0] if len(cands) == 1 else None
        p = Path(obj)
        if not p.is_absolute():
            p = link_dir / p
        return p.with_suffix(".su")  # GCC names it after the object, last suffix replaced

    @staticmethod
    def _prologue_frame(f):
        """Every push and sub sp of a function summed (library code has no
        .su): an upper bound, as a later push may follow a pop."""
        frame = 0
        for i in f.insns:
            if i.op == "push":
                frame += 4 * _reglist_len(i.args)
            elif i.op == "sub" and i.args.replace(" ", "").startswith("sp,"):
                m = re.search(r"#(\d+)", i.args)
                if m:
                    frame += int(m.group(1))
            elif i.op == "add" and i.args.replace(" ", "").startswith("sp,r"):
                frame += 1 << 30  # sp moved by a register: not bounded by reading
        return frame

    def by_name(self, name):
        """Functions a config name denotes: "fn" or "fn@object.c.obj"; a
        clone suffix (.isra.0) is matched too. The function part may be a
        shell pattern ("km_rd_*": every read hook of a table), so a table
        of callbacks named alike needs no entry per callback."""
        want, _, obj = name.partition("@")
        pattern = any(ch in want for ch in "*?[")
        out = []
        for f in self.funcs.values():
            for n in f.names:
                base = re.sub(CLONE_SUFFIX, "", n)
                if n == want or base == want or (pattern and fnmatch.fnmatchcase(base, want)):
                    # An LTO partition names no source object: the function
                    # name alone is matched (every same-named static: more
                    # edges, never fewer).
                    if not obj or (f.obj and (f.obj.rstrip(")").endswith(obj) or self._lto_source_is(f, obj))):
                        out.append(f)
                    break
        return out

    def inline_origins(self, addrs):
        """For each address, the function its code comes from in the source
        (innermost of the debug info's inline chain) and that function's
        file: {addr: (name, file)}; empty without debug information."""
        if not addrs:
            return {}
        out = run("addr2line", "-a", "-f", "-i", "-e", str(self.elf), *[hex(a) for a in addrs])
        origins, cur, lines, k = {}, None, out.splitlines(), 0
        while k < len(lines):
            if re.match(r"^0x[0-9a-f]+$", lines[k]):
                cur = int(lines[k], 16)
                k += 1
                continue
            if cur is not None and cur not in origins and k + 1 < len(lines) and not lines[k].startswith("??"):
                origins[cur] = (lines[k], Path(lines[k + 1].split(":")[0]).name)
            k += 2
        return origins

    @staticmethod
    def _lto_source_is(f, obj):
        """An LTO partition's function matches "x.c.obj" if its source is x.c
        (or, without debug information, always)."""
        if not is_lto_partition(f.obj):
            return False
        return f.src is None or f.src == re.sub(r"\.(obj|o)$", "", Path(obj).name)

    def vectors(self, section_start, count):
        """Handler addresses of the vector table (entry 0 is the initial SP)."""
        words = self.read_words([section_start + 4 * k for k in range(count)])
        return [words.get(section_start + 4 * k) for k in range(count)]


def _reglist_len(args):
    regs = args.strip().strip("{}").replace(" ", "").split(",")
    n = 0
    for r in regs:
        if "-" in r:
            a, b = r.split("-")
            n += int(b[1:]) - int(a[1:]) + 1
        elif r:
            n += 1
    return n
