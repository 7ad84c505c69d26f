#!/usr/bin/env python3
"""The demo's package list (scripts/setup --demo) against what the demo builds and runs, both ways:
- every package on the list owns a file the demo's build reads (a header, a library it links, the compiler, cmake,
  ninja, pkg-config) or a command the demo runs (gnuplot, bc): a package nothing needs fails;
- every package owning such a file is on the list or among the packages the list's packages depend on (their
  Depends and Pre-Depends, recursively, as dpkg has them installed): a need the list does not bring fails.
The files are the build's own record: `ninja -t inputs` of lever-hil, lever-fw-sim and lever-study (objects,
libraries) and `ninja -t deps` of their objects (every header the compiler read).

usage: demo_packages.py REPO_ROOT BUILD_DIR   (BUILD_DIR: lever-hil, lever-fw-sim and lever-study built in it)
"""
import os
import re
import shutil
import subprocess
import sys

# Commands scripts/demo runs besides the programs it builds: bc in the script, gnuplot from lever-hil's sweeps and
# lever-study's plots.
DEMO_COMMANDS = ["bc", "gnuplot"]


def out(*args, cwd=None):
    return subprocess.run(args, cwd=cwd, check=True, capture_output=True, text=True).stdout


def chain(path):
    """The path and every link it goes through (/usr/bin/c++ -> /etc/alternatives/c++ -> /usr/bin/g++ -> ...)."""
    seen = [path]
    while os.path.islink(seen[-1]) and len(seen) < 20:
        target = os.readlink(seen[-1])
        seen.append(os.path.normpath(os.path.join(os.path.dirname(seen[-1]), target)))
    return seen


def owners(paths):
    """Package of each path dpkg knows ({path: {package}}); paths no package owns are left out."""
    found = {}
    paths = sorted(set(paths))
    for i in range(0, len(paths), 500):
        r = subprocess.run(["dpkg-query", "-S", *paths[i:i + 500]], capture_output=True, text=True)
        for line in r.stdout.splitlines():
            if line.startswith("diversion by"):
                continue
            packages, _, path = line.partition(": ")
            for p in packages.split(", "):
                found.setdefault(path, set()).add(p.split(":")[0])
    return found


def installed():
    """{package: (depends text, provides text)} of the installed packages."""
    table = {}
    text = out("dpkg-query", "-W", "-f", "${Package}\t${db:Status-Abbrev}\t${Pre-Depends}, ${Depends}\t${Provides}\n")
    for line in text.splitlines():
        name, status, depends, provides = line.split("\t")
        if status.startswith("ii"):
            table[name] = (depends, provides)
    return table


def closure(roots, table):
    providers = {}
    for name, (_, provides) in table.items():
        for p in filter(None, (x.strip() for x in provides.split(","))):
            providers.setdefault(re.split(r"[ (:]", p)[0], set()).add(name)
    done, todo = set(), list(roots)
    while todo:
        name = todo.pop()
        if name in done or name not in table:
            continue
        done.add(name)
        for clause in filter(None, (c.strip() for c in table[name][0].split(","))):
            for alternative in clause.split("|"):  # the first alternative that is installed
                dep = re.split(r"[ (:]", alternative.strip())[0]
                if dep in table:
                    todo.append(dep)
                    break
                if dep in providers:
                    todo.extend(providers[dep])
                    break
    return done


def main(root, build):
    demo = out(os.path.join(root, "scripts", "setup"), "--demo", "--list").split()
    inputs = out("ninja", "-t", "inputs", "bin/lever-hil", "bin/lever-fw-sim", "bin/lever-study", cwd=build).split()
    objects = [i for i in inputs if i.endswith(".o")]
    files = [os.path.abspath(os.path.join(build, i)) for i in inputs if not i.endswith(".o")]
    deps = out("ninja", "-t", "deps", *objects, cwd=build)
    headers = [line.strip() for line in deps.splitlines() if line.startswith("    ")]
    if len(headers) < 100:
        print(f"FAILED: ninja recorded {len(headers)} headers for the demo's objects: build them first")
        return 1
    files += [os.path.abspath(os.path.join(build, h)) for h in headers]
    cache = open(os.path.join(build, "CMakeCache.txt")).read()
    for key in ("CMAKE_CXX_COMPILER:FILEPATH", "CMAKE_MAKE_PROGRAM:FILEPATH", "PKG_CONFIG_EXECUTABLE:FILEPATH",
                "CMAKE_COMMAND:INTERNAL"):
        m = re.search(rf"^{re.escape(key)}=(.*)$", cache, re.M)
        files.append(m.group(1))
    for command in DEMO_COMMANDS:
        files.append(shutil.which(command) or f"/usr/bin/{command}")
    files = [p for f in files if f.startswith("/") and not f.startswith(root) for p in chain(f)]
    needed = {}
    for path, packages in owners(files).items():
        for p in packages:
            needed.setdefault(p, path)
    failed = 0
    for p in demo:
        if p not in needed:
            print(f"FAILED: {p} is on the demo's list, but nothing the demo builds or runs needs it")
            failed += 1
    brought = closure(demo, installed())
    for p, path in sorted(needed.items()):
        if p not in brought:
            print(f"FAILED: the demo needs {p} ({path}), which scripts/setup --demo does not bring")
            failed += 1
    print(f"demo packages: {len(demo)} on the list; {len(needed)} packages own the {len(set(files))} files the "
          f"demo's build reads and runs; the list brings {len(brought)} packages")
    print(f"demo packages: {len(demo) + len(needed) - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    if len(sys.argv) != 3:
        print("usage: demo_packages.py REPO_ROOT BUILD_DIR", file=sys.stderr)
        sys.exit(2)
    sys.exit(main(os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])))
