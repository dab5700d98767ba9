#!/usr/bin/env python3
"""The documentation agrees with the code: every documented example loads, every named file exists, and
docs/cli.md documents exactly the commands and options the CLI has.

Usage: test_doc_examples.py SPECULA_BINARY SOURCE_DIR [--jobs N] [--only abcd]

Pages: README.md, docs/*.md and docs/validation/*.md. Standard library only. Checks:

(a) Every ```json block is parsed and classified:
      * a scene (an object with "camera" or "shapes"): `specula info` must accept it;
      * a material (an object with "nodes" and "output"; every node's example in docs/nodes.md): it is wrapped as
        {"materials": {"example": BLOCK}} and `specula bsdf` shades one query with it, then `specula glsl` emits it;
      * a materials file (an object with only "materials"): `specula bsdf --material M` for each material;
      * other JSON (a manifest, a progress event, ...): listed as SKIP with its keys, not loaded;
      * a block that is not valid JSON fails, unless the line before it is the marker
        `<!-- doc-test: skip REASON -->`, which is reported as SKIP with its reason (so fragments stay visible).
    The block is written to a temporary folder; string values that are existing paths relative to the repository
    root (the docs' convention for files in examples, e.g. "examples/lean/bumps.png") are made absolute first.
(b) Every examples/....json named in the pages exists, and `specula info` accepts it and every other scene under
    examples/; the README's Layout rows for `examples/` and `tools/` name every entry of those folders (scenes and
    folders of examples/, files and folders of tools/) and nothing that is not there.
(c) Every path tools/..., examples/..., scripts/..., docs/..., tests/..., plugin/..., nodes/..., core/... in the
    pages exists (globs and {a,b} alternatives expanded; a source module named by its stem, core/x/y for
    core/x/y.h or .cpp, counts), and so does every relative Markdown link or image target, with its #anchor
    (GitHub's heading slugs) when it points into a Markdown page.
(d) Every `specula COMMAND` named in docs/cli.md is a subcommand of `specula --help`, and every --option there is
    one of that command's options (`specula COMMAND --help`): the command is the one named earlier on the same
    line, else the one a synopsis line in the same code block started with, else the `## specula COMMAND` section;
    options without any of these must belong to some command. Conversely every subcommand and every option the CLI
    prints appears in docs/cli.md for that command (its short alias, e.g. -o for --output, counts).
Failures are listed with file:line. Ends with 'N passed, M failed'; exits 1 if anything failed.
"""
import concurrent.futures
import glob
import json
import os
import re
import subprocess
import sys
import tempfile

PASSED = 0
FAILED = 0
FAILURES = []
SKIPS = []


def check(ok, where, text):
    global PASSED, FAILED
    if ok:
        PASSED += 1
    else:
        FAILED += 1
        FAILURES.append(f"{where}: {text}")
        print(f"FAIL {where}: {text}", flush=True)
    return ok


def skip(where, text):
    SKIPS.append(f"{where}: {text}")
    print(f"SKIP {where}: {text}", flush=True)


def run(cmd, cwd=None, timeout=300):
    try:
        p = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        return -1, "", f"timed out after {timeout} s"


# ---- pages ---------------------------------------------------------------------------------------------------------

def pages(src):
    files = [os.path.join(src, "README.md")]
    files += sorted(glob.glob(os.path.join(src, "docs", "*.md")))
    files += sorted(glob.glob(os.path.join(src, "docs", "validation", "*.md")))
    return files


def rel(src, path):
    return os.path.relpath(path, src)


def fenced_blocks(lines):
    """(start line number 1-based of the opening fence, language, [lines], marker text or None)."""
    blocks = []
    i = 0
    while i < len(lines):
        m = re.match(r"^(\s*)(```+)\s*([\w+-]*)\s*$", lines[i])
        if m:
            fence, lang, start = m.group(2), m.group(3), i
            body = []
            i += 1
            while i < len(lines) and not re.match(r"^\s*" + fence + r"\s*$", lines[i]):
                body.append(lines[i])
                i += 1
            k = start - 1
            while k >= 0 and not lines[k].strip():
                k -= 1
            marker = None
            if k >= 0:
                mm = re.match(r"^\s*<!--\s*doc-test:\s*skip\b\s*(.*?)\s*-->\s*$", lines[k])
                if mm:
                    marker = mm.group(1) or "(no reason given)"
            blocks.append((start + 1, lang, body, marker))
        i += 1
    return blocks


def in_code_mask(lines):
    """Per line: True inside a fenced block (fence lines included)."""
    mask = []
    inside = None
    for line in lines:
        m = re.match(r"^\s*(```+)", line)
        if inside is None and m:
            inside = m.group(1)
            mask.append(True)
        elif inside is not None and re.match(r"^\s*" + inside + r"\s*$", line):
            inside = None
            mask.append(True)
        else:
            mask.append(inside is not None)
    return mask


# ---- (a) JSON blocks -----------------------------------------------------------------------------------------------

def absolutise(value, src):
    """String values naming an existing path relative to the repository root become absolute."""
    if isinstance(value, dict):
        return {k: absolutise(v, src) for k, v in value.items()}
    if isinstance(value, list):
        return [absolutise(v, src) for v in value]
    if isinstance(value, str) and value and not value.startswith(("@", "/", "generate:")) and "/" in value:
        p = os.path.join(src, value)
        if os.path.exists(p):
            return p
    return value


def load_material_file(specula, path, names, jobs_dir):
    """`specula bsdf` (one query per material) and `specula glsl`; returns a list of (ok, message)."""
    results = []
    for name in names:
        rc, out, err = run([specula, "bsdf", path, "--material", name, "--wo", "0,0.6,0.8", "--wi", "0.3,0,0.954"])
        ok = rc == 0
        if ok:
            try:
                ans = json.loads(out)
                ok = "f" in ans and "pdf" in ans
                if not ok:
                    err = "answer without f/pdf: " + out[:200]
            except ValueError:
                ok, err = False, "bsdf printed no JSON: " + out[:200]
        results.append((ok, f"material '{name}': specula bsdf exit {rc}: {err.strip()[:600]}"))
        glsl = os.path.join(jobs_dir, os.path.basename(path) + "." + name + ".glsl")
        rc, out, err = run([specula, "glsl", path, "--material", name, "-o", glsl])
        results.append((rc == 0 and os.path.getsize(glsl) > 0 if rc == 0 else False,
                        f"material '{name}': specula glsl exit {rc}: {err.strip()[:600]}"))
    return results


def check_json_blocks(specula, src, tmp, jobs):
    tasks = []  # (where, kind, path, material names)
    counts = {"scene": 0, "material": 0, "materials": 0}
    for page in pages(src):
        lines = open(page, encoding="utf-8").read().split("\n")
        for n, (line, lang, body, marker) in enumerate(fenced_blocks(lines)):
            if lang != "json":
                continue
            where = f"{rel(src, page)}:{line}"
            if marker is not None:
                skip(where, f"marked fragment: {marker}")
                continue
            try:
                block = json.loads("\n".join(body))
            except ValueError as e:
                check(False, where, f"```json block is not valid JSON ({e}); make it whole, or mark a deliberate "
                                    "fragment with '<!-- doc-test: skip REASON -->' on the line before")
                continue
            if not isinstance(block, dict):
                skip(where, "JSON that is not an object: not a scene or material")
                continue
            block = absolutise(block, src)
            base = re.sub(r"[^\w]+", "_", rel(src, page)) + f"_{line}"
            if "camera" in block or "shapes" in block:
                path = os.path.join(tmp, base + ".scene.json")
                json.dump(block, open(path, "w"))
                tasks.append((where, "scene", path, None))
                counts["scene"] += 1
            elif "nodes" in block and "output" in block:
                path = os.path.join(tmp, base + ".material.json")
                json.dump({"materials": {"example": block}}, open(path, "w"))
                tasks.append((where, "material", path, ["example"]))
                counts["material"] += 1
            elif set(block) == {"materials"} and isinstance(block["materials"], dict):
                path = os.path.join(tmp, base + ".materials.json")
                json.dump(block, open(path, "w"))
                tasks.append((where, "materials", path, sorted(block["materials"])))
                counts["materials"] += 1
            else:
                skip(where, "JSON that is not a scene or material (keys: " + ", ".join(sorted(block)[:6]) + ")")

    def work(task):
        where, kind, path, names = task
        if kind == "scene":
            rc, out, err = run([specula, "info", path])
            return where, [(rc == 0, f"scene: specula info exit {rc}: {err.strip()[:600]}")]
        return where, load_material_file(specula, path, names, tmp)

    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as ex:
        for where, results in ex.map(work, tasks):
            for ok, msg in results:
                check(ok, where, msg)
    print(f"(a) json blocks: {counts['scene']} scenes, {counts['material']} materials, "
          f"{counts['materials']} materials files loaded", flush=True)
    return len(tasks)


# ---- (b) examples --------------------------------------------------------------------------------------------------

def check_examples(specula, src, jobs):
    named = {}  # path -> first where
    for page in pages(src):
        for i, line in enumerate(open(page, encoding="utf-8").read().split("\n"), 1):
            for m in re.finditer(r"(?<![\w./-])(examples/[\w./-]+?\.json)\b", line):
                named.setdefault(m.group(1), f"{rel(src, page)}:{i}")
    # every scene under examples/ is loaded too, named or not (the README promises all of them)
    for p in sorted(glob.glob(os.path.join(src, "examples", "**", "*.json"), recursive=True)):
        named.setdefault(rel(src, p), "examples/ (every scene)")

    def work(item):
        path, where = item
        full = os.path.join(src, path)
        if not os.path.isfile(full):
            return where, [(False, f"{path} is named but does not exist")]
        rc, out, err = run([specula, "info", full])
        return where, [(rc == 0, f"{path}: specula info exit {rc}: {err.strip()[:600]}")]

    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as ex:
        for where, results in ex.map(work, sorted(named.items())):
            for ok, msg in results:
                check(ok, where, msg)
    print(f"(b) example scenes: {len(named)} loaded with specula info", flush=True)

    # README Layout rows: `examples/` and `tools/` list their folders' contents
    readme = os.path.join(src, "README.md")
    lines = open(readme, encoding="utf-8").read().split("\n")
    for folder, want in (("examples", lambda e, d: d or e.endswith(".json")), ("tools", lambda e, d: True)):
        rows = [(i, l) for i, l in enumerate(lines, 1) if l.startswith(f"| `{folder}/` |")]
        if not check(len(rows) == 1, "README.md", f"one Layout row for `{folder}/` (found {len(rows)})"):
            continue
        i, row = rows[0]
        cell = row.split("|", 2)[2]
        names = set()
        for m in re.finditer(r"`([^`]+)`", cell):
            t = m.group(1)
            if re.match(r"^[\w.-]+/?$", t):
                names.add(t.rstrip("/"))
        entries = set()
        for e in os.listdir(os.path.join(src, folder)):
            d = os.path.isdir(os.path.join(src, folder, e))
            if e.startswith(".") or e == "__pycache__":
                continue
            if want(e, d):
                entries.add(e)
        for e in sorted(entries - names):
            check(False, f"README.md:{i}", f"the `{folder}/` row does not name {folder}/{e}")
        for e in sorted(names - entries):
            check(os.path.exists(os.path.join(src, folder, e)), f"README.md:{i}",
                  f"the `{folder}/` row names `{e}`, which is not in {folder}/")
        check(True, f"README.md:{i}", f"`{folder}/` row")
        print(f"(b) README `{folder}/` row: {len(entries)} entries, {len(names)} named", flush=True)


# ---- (c) paths and links -------------------------------------------------------------------------------------------

PATH_RE = re.compile(r"(?<![\w./@:-])((?:tools|examples|scripts|docs|tests|plugin|nodes|core|bench|data|include)/"
                     r"[\w.*{},/-]*)")


def expand_braces(p):
    m = re.search(r"\{([^{}]*)\}", p)
    if not m:
        return [p]
    out = []
    for alt in m.group(1).split(","):
        out += expand_braces(p[:m.start()] + alt + p[m.end():])
    return out


def slug(heading):
    """GitHub's heading anchor: lower case, punctuation except - and _ dropped, spaces to -."""
    h = re.sub(r"`", "", heading.strip().lower())
    h = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", h)
    return "".join(c for c in h if c.isalnum() or c in "-_ ").replace(" ", "-")


ANCHORS = {}


def anchors(path):
    if path not in ANCHORS:
        seen = {}
        out = set()
        lines = open(path, encoding="utf-8").read().split("\n")
        mask = in_code_mask(lines)
        for line, code in zip(lines, mask):
            m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
            if m and not code:
                s = slug(m.group(1))
                k = seen.get(s, 0)
                seen[s] = k + 1
                out.add(s if k == 0 else f"{s}-{k}")
            for a in re.finditer(r"<a\s+(?:name|id)=\"([^\"]+)\"", line):
                out.add(a.group(1))
        ANCHORS[path] = out
    return ANCHORS[path]


def check_paths(src):
    n_paths = n_links = 0
    for page in pages(src):
        text = open(page, encoding="utf-8").read()
        lines = text.split("\n")
        for i, line in enumerate(lines, 1):
            where = f"{rel(src, page)}:{i}"
            for m in PATH_RE.finditer(line):
                p = m.group(1).rstrip(".,")
                n_paths += 1
                alts = expand_braces(p)
                for a in alts:
                    hits = glob.glob(os.path.join(src, a)) if "*" in a else [os.path.join(src, a)]
                    # a source module named by its stem ("core/texture/normal_map_gen") counts if its .h/.cpp exists
                    hits += [h + ext for h in hits for ext in (".h", ".cpp")]
                    check(any(os.path.exists(h) for h in hits), where, f"path {a} does not exist")
            for m in re.finditer(r"!?\[[^\]]*\]\(([^)\s]+)\)", line):
                target = m.group(1)
                if re.match(r"^[a-z]+:", target):
                    continue
                n_links += 1
                path, _, anchor = target.partition("#")
                full = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
                if not check(os.path.exists(full), where, f"link target {target} does not exist"):
                    continue
                if anchor and full.endswith(".md"):
                    check(anchor in anchors(full), where, f"link {target}: no heading #{anchor} in {rel(src, full)}")
    print(f"(c) paths: {n_paths} repository paths, {n_links} links checked", flush=True)


# ---- (d) CLI commands and options ----------------------------------------------------------------------------------

def help_options(text, aliases=None):
    aliases = {} if aliases is None else aliases
    """Long options and subcommands of a CLI11 help text; short aliases (-o -> --output) go into `aliases`."""
    opts, subs = set(), set()
    section = None
    for line in text.split("\n"):
        if re.match(r"^\S.*:\s*$", line):
            section = line.strip().rstrip(":").lower()
            continue
        if section is None:
            continue
        if section.startswith("subcommand"):
            m = re.match(r"^\s+([a-z][\w-]*)\s", line + " ")
            if m:
                subs.add(m.group(1))
        elif section.startswith("option") or section.startswith("flag"):
            m = re.match(r"^\s+((?:-\w,)?(?:--[\w-]+)(?:,--[\w-]+)*)", line)
            if m:
                longs = re.findall(r"--[\w-]+", m.group(1))
                opts.update(longs)
                short = re.match(r"-(\w),", m.group(1))
                if short:
                    for o in longs:
                        aliases["-" + short.group(1)] = o
    return opts, subs


def check_cli(specula, src):
    rc, top, err = run([specula, "--help"])
    check(rc == 0, "specula --help", f"exit {rc}: {err.strip()}")
    top_opts, commands = help_options(top)
    check(len(commands) > 0, "specula --help", "lists subcommands")
    cmd_opts = {}
    cmd_aliases = {}  # command -> {"-o": "--output"}: documenting the short form documents the option
    for c in sorted(commands):
        rc, out, err = run([specula, c, "--help"])
        check(rc == 0, f"specula {c} --help", f"exit {rc}: {err.strip()}")
        cmd_aliases[c] = {}
        cmd_opts[c] = help_options(out, cmd_aliases[c])[0]
    all_opts = set(top_opts).union(*cmd_opts.values())

    page = os.path.join(src, "docs", "cli.md")
    lines = open(page, encoding="utf-8").read().split("\n")
    mask = in_code_mask(lines)
    documented = {c: set() for c in commands}
    documented_any = set()
    commands_named = set()
    section = None
    block_cmd = None
    n_opts = 0
    for i, (line, code) in enumerate(zip(lines, mask), 1):
        where = f"docs/cli.md:{i}"
        h = re.match(r"^#{1,6}\s+(.*)$", line)
        if h and not code:
            hm = re.match(r"^##\s+specula\s+([a-z][\w-]*)\s*$", line)
            if hm or line.startswith("## "):
                section = hm.group(1) if hm else None
            if hm:
                commands_named.add(hm.group(1))
                check(hm.group(1) in commands, where, f"section of unknown command 'specula {hm.group(1)}'")
        if re.match(r"^\s*```", line):
            block_cmd = None
            continue
        # commands named in code (blocks, or `spans`)
        code_texts = [line] if code else re.findall(r"`([^`]*)`", line)
        cmd_positions = []
        for text in code_texts:
            for m in re.finditer(r"(?<![\w/.-])specula\s+([a-z][a-z-]*)\b", text):
                c = m.group(1)
                commands_named.add(c)
                check(c in commands, where, f"'specula {c}': no such subcommand (specula --help lists "
                                            f"{', '.join(sorted(commands))})")
        for m in re.finditer(r"(?<![\w/.-])specula\s+([a-z][a-z-]*)\b", line):
            cmd_positions.append((m.start(), m.group(1)))
        if code:
            if cmd_positions and re.match(r"^specula\s", line.strip()):
                block_cmd = cmd_positions[0][1]
            elif line and not line[0].isspace():
                block_cmd = None
        for m in re.finditer(r"(?<![\w-])(--[a-z][\w-]*|-[a-z](?=[\s,`|]))", line):
            o = m.group(1)
            short = not o.startswith("--")
            n_opts += 1
            ctx = None
            for pos, c in cmd_positions:
                if pos < m.start():
                    ctx = c
            if ctx is None and code:
                ctx = block_cmd
            if ctx is None:
                ctx = section
            if short:  # a short alias counts where the command has it (-o); other "-x" text is not an option
                if ctx in cmd_aliases and o in cmd_aliases[ctx]:
                    documented[ctx].add(cmd_aliases[ctx][o])
                continue
            if ctx in cmd_opts:
                ok = o in cmd_opts[ctx] or o in top_opts
                check(ok, where, f"'{o}' is not an option of 'specula {ctx}' (its --help lists "
                                 f"{', '.join(sorted(cmd_opts[ctx]))})")
                if ok:
                    documented[ctx].add(o)
            else:
                check(o in all_opts, where, f"'{o}' is not an option of any specula command")
            documented_any.add(o)
    for c in sorted(commands):
        check(c in commands_named, "docs/cli.md", f"subcommand 'specula {c}' (from specula --help) is not documented")
        for o in sorted(cmd_opts[c] - {"--help"}):
            check(o in documented[c], "docs/cli.md", f"option '{o}' of 'specula {c}' (from its --help) is not "
                                                     f"documented for that command")
    for o in sorted(top_opts - {"--help"}):
        check(o in documented_any, "docs/cli.md", f"global option '{o}' is not documented")
    print(f"(d) cli: {len(commands)} subcommands, {sum(len(v) for v in cmd_opts.values())} options of the CLI; "
          f"{n_opts} option mentions in docs/cli.md checked", flush=True)


def main():
    args = sys.argv[1:]
    jobs = os.cpu_count() or 2
    if "--jobs" in args:
        k = args.index("--jobs")
        jobs = int(args[k + 1])
        del args[k:k + 2]
    only = "abcd"
    if "--only" in args:
        k = args.index("--only")
        only = args[k + 1]
        del args[k:k + 2]
    if len(args) != 2:
        print(__doc__)
        return 2
    specula, src = os.path.abspath(args[0]), os.path.abspath(args[1])
    with tempfile.TemporaryDirectory(prefix="specula-doc-examples-") as tmp:
        # Texture and P-NDF caches: the ctest environment's folder, else a scratch folder, never ~/.cache.
        os.environ.setdefault("SPECULA_CACHE_DIR", os.path.join(tmp, "cache"))
        if "a" in only:
            check_json_blocks(specula, src, tmp, jobs)
        if "b" in only:
            check_examples(specula, src, jobs)
        if "c" in only:
            check_paths(src)
        if "d" in only:
            check_cli(specula, src)
    if SKIPS:
        print(f"{len(SKIPS)} skipped (see SKIP lines above)")
    if FAILURES:
        print("\nFailures:")
        for f in FAILURES:
            print("  " + f)
    print(f"{PASSED} passed, {FAILED} failed")
    return 1 if FAILED else 0


if __name__ == "__main__":
    sys.exit(main())
