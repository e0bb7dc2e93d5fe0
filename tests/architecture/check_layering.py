#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The module layering, read from the sources (docs/architecture.md).

    check_layering.py SOURCE_DIR MODULES_TXT

MODULES_TXT (written by tests/CMakeLists.txt) has a line "module: uses..." per
module, as src/sss/CMakeLists.txt declares them. The build itself refuses a
wrong-way include in a module's, a tool's or the Python module's sources
(sss_deny_higher_modules); this check covers what the build cannot see and
what it does not compile on its own:

  - the declarations: what a module uses is closed (it lists what its uses use);
  - each module's "May use:" sentence (one per module, in its headers) names
    exactly the modules CMake lets it use;
  - every #include "sss/<m>/..." in include/, src/, python/, tests/, bench/
    names an existing module header, from a file allowed to use <m>: a
    module's headers and sources use it and what it uses; a tool, its
    modules and cli; the Python module what python/CMakeLists.txt grants;
    tests/<m>/ the module it tests and what that uses; tests/integration/,
    tests/fuzz/ and bench/ any module (they test the pipeline whole);
  - a module's private headers (src/sss/<m>/*.h) are included only from
    src/sss/<m>/ and its white-box tests in tests/<m>/.

Every violation is listed with file and line; exit 1 if there is any.
"""
import pathlib
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]')
PUBLIC = re.compile(r"^sss/(\w+)/")
PRIVATE = re.compile(r"(?:^|/)src/sss/(\w+)/")
SOURCES = (".cpp", ".h", ".inl")


def read_uses(path):
    uses = {}
    for line in pathlib.Path(path).read_text().splitlines():
        if ":" in line:
            name, rest = line.split(":", 1)
            uses[name.strip()] = set(rest.split())
    return uses


def closure(uses, modules):
    seen = set(modules)
    todo = list(modules)
    while todo:
        for dep in uses.get(todo.pop(), ()):
            if dep not in seen:
                seen.add(dep)
                todo.append(dep)
    return seen


def may_use_sentences(root, uses, errors):
    """Each module's '/// May use: ...' sentence against the declarations."""
    for module, declared in sorted(uses.items()):
        found = []
        for header in sorted((root / "include/sss" / module).glob("*.h")):
            lines = header.read_text().splitlines()
            for i, line in enumerate(lines):
                if not line.startswith("/// May use:"):
                    continue
                text = line[len("/// May use:"):]
                j = i + 1
                while "." not in text and j < len(lines) and lines[j].startswith("///"):
                    text += " " + lines[j][3:]
                    j += 1
                text = re.sub(r"\([^)]*\)", "", text.split(".")[0])
                named = {w for w in re.findall(r"\w+", text) if w in uses}
                found.append((header.relative_to(root), i + 1, named))
        if len(found) != 1:
            where = ", ".join(f"{f}:{n}" for f, n, _ in found) or "none"
            errors.append(f"module {module}: {len(found)} '/// May use:' sentences ({where}); "
                          "its main header needs exactly one")
            continue
        header, line, named = found[0]
        if named != declared:
            errors.append(f"{header}:{line}: 'May use:' names {sorted(named) or 'no module'}, "
                          f"src/sss/CMakeLists.txt declares {sorted(declared) or 'none'}")


def tool_modules(root):
    """tool -> the modules it links, from the top CMakeLists.txt."""
    text = (root / "CMakeLists.txt").read_text()
    return {tool: {"cli", *re.findall(r"sss_(\w+)", deps)}
            for tool, deps in re.findall(r"^sss_add_tool\((\w+)([^)]*)\)", text, re.M)}


def python_modules(root):
    text = (root / "python/CMakeLists.txt").read_text()
    # One call for every interpreter's extension target (sss_python_module()).
    match = re.search(r"sss_deny_higher_modules\(\$\{target\}([^)]*)\)", text)
    return set(match.group(1).split()) if match else set()


def allowed_for(rel, uses, tools, python):
    """(modules whose public headers rel may include, module whose private
    headers it may include) or None for a file the check does not govern."""
    parts = rel.parts
    everything = set(uses)
    if parts[:2] in (("src", "sss"), ("include", "sss")) and len(parts) > 3:
        module = parts[2]
        return closure(uses, {module}), module
    if parts[0] == "src" and len(parts) == 3 and parts[1] in tools:
        return closure(uses, tools[parts[1]]), None
    if parts[0] == "python":
        return closure(uses, python), None
    if parts[0] == "tests" and len(parts) > 2:
        group = parts[1]
        if group in uses:
            return closure(uses, {group}), group
        if group in ("integration", "fuzz"):
            return everything, None
        if group == "cli":
            return closure(uses, {"cli"}), None
        return everything, None
    if parts[0] == "bench":
        return everything, None
    return None


def check_includes(root, uses, errors):
    tools = tool_modules(root)
    python = python_modules(root)
    files = []
    for top in ("include", "src", "python", "tests", "bench"):
        files += [p for p in (root / top).rglob("*") if p.suffix in SOURCES and p.is_file()]
    for path in sorted(files):
        rel = path.relative_to(root)
        rule = allowed_for(rel, uses, tools, python)
        if rule is None:
            continue
        allowed, own = rule
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            match = INCLUDE.match(line)
            if not match:
                continue
            name = match.group(1)
            public = PUBLIC.match(name)
            if public:
                module = public.group(1)
                if not (root / "include" / name).is_file():
                    errors.append(f"{rel}:{number}: {name} is no module header")
                elif module not in allowed:
                    errors.append(f"{rel}:{number}: includes {name}, but may use only "
                                  f"{', '.join(sorted(allowed))}")
                continue
            private = PRIVATE.search(name)
            if private is None and "/" not in name and rel.parts[0] == "src":
                continue  # a header beside the file
            if private and private.group(1) != own:
                errors.append(f"{rel}:{number}: includes {name}, a private header of module "
                              f"{private.group(1)}")


def main():
    if len(sys.argv) != 3:
        print(__doc__.splitlines()[2].strip(), file=sys.stderr)
        return 2
    root = pathlib.Path(sys.argv[1]).resolve()
    uses = read_uses(sys.argv[2])
    errors = []
    for module, declared in sorted(uses.items()):
        missing = closure(uses, declared) - declared - {module}
        if missing:
            errors.append(f"src/sss/CMakeLists.txt: {module} uses {sorted(declared)} but not "
                          f"what they use: {sorted(missing)}")
        if module in closure(uses, declared):
            errors.append(f"src/sss/CMakeLists.txt: {module} uses itself through {sorted(declared)}")
    may_use_sentences(root, uses, errors)
    check_includes(root, uses, errors)
    for error in errors:
        print(f"FAIL: {error}", file=sys.stderr)
    print(f"layering: {len(uses)} modules, {len(errors)} violation(s)")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
