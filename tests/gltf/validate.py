#!/usr/bin/env python3
"""Khronos glTF-Validator (npm package gltf-validator) on every valid generated file.

Usage: validate.py DATADIR PREFIX
Installs nodejs/npm (apt-get) and gltf-validator (npm, under PREFIX) when missing,
then validates each file of DATADIR/valid.txt; fails on any error-severity message.
"""
import json
import os
import shutil
import subprocess
import sys

# The validator's Node API: reports as JSON on stdout, one file per argument.
RUNNER = r"""
const fs = require('fs'), path = require('path');
const validator = require('gltf-validator');
(async () => {
  for (const file of process.argv.slice(2)) {
    const data = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(data, {
      uri: path.basename(file),
      externalResourceFunction: (uri) => new Promise((resolve, reject) => {
        try { resolve(new Uint8Array(fs.readFileSync(path.join(path.dirname(file), decodeURIComponent(uri))))); }
        catch (e) { reject(e.toString()); }
      }),
    });
    console.log(JSON.stringify({file: path.basename(file), issues: report.issues}));
  }
})().catch((e) => { console.error(e); process.exit(2); });
"""


def run(cmd, **kw):
    print("+", " ".join(cmd), flush=True)
    subprocess.run(cmd, check=True, **kw)


def ensure_validator(prefix):
    if not shutil.which("node") or not shutil.which("npm"):
        sudo = [] if os.geteuid() == 0 else ["sudo"]
        run(sudo + ["apt-get", "update", "-q"])
        run(sudo + ["apt-get", "install", "-y", "-q", "nodejs", "npm"], env=dict(os.environ, DEBIAN_FRONTEND="noninteractive"))
    if not os.path.isdir(os.path.join(prefix, "node_modules", "gltf-validator")):
        os.makedirs(prefix, exist_ok=True)
        run(["npm", "install", "--prefix", prefix, "--no-audit", "--no-fund", "gltf-validator"])


def main():
    data, prefix = sys.argv[1], os.path.abspath(sys.argv[2])
    ensure_validator(prefix)
    with open(os.path.join(data, "valid.txt")) as f:
        files = [os.path.join(data, line.strip()) for line in f if line.strip()]
    runner = os.path.join(prefix, "validate.js")
    with open(runner, "w") as f:
        f.write(RUNNER)
    out = subprocess.run(["node", runner] + files, check=True, capture_output=True, text=True,
                         env=dict(os.environ, NODE_PATH=os.path.join(prefix, "node_modules"))).stdout
    failed = False
    for line in out.splitlines():
        r = json.loads(line)
        iss = r["issues"]
        print("%s: %d errors, %d warnings, %d infos, %d hints" % (r["file"], iss["numErrors"], iss["numWarnings"],
                                                                 iss["numInfos"], iss["numHints"]))
        for m in iss["messages"]:
            if m["severity"] <= 1:  # 0 error, 1 warning
                print("  %s %s %s: %s" % (["ERROR", "warning"][m["severity"]], m["code"], m.get("pointer", ""),
                                          m["message"]))
        failed |= iss["numErrors"] > 0
    if len(out.splitlines()) != len(files):
        print("validator reported on %d of %d files" % (len(out.splitlines()), len(files)))
        failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
