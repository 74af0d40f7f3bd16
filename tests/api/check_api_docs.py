#!/usr/bin/python3
"""Validates every example in docs/api.md against docs/api.schema.json.

Examples are fenced blocks whose info string is "json request", "json reply [command]" or
"json event". A reply tagged with a command is also checked against that command's result
schema. Every request and every event the schema describes must have at least one example,
and every command at least one tagged reply. Prints every mismatch with the example's line
number and exits non-zero if there was one.
"""
import json
import re
import sys

import jsonschema


def main(docs_path, schema_path):
    schema = json.load(open(schema_path, encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)

    def validator(ref):
        return jsonschema.Draft202012Validator(
            {"$schema": schema["$schema"], "$defs": schema["$defs"], "$ref": ref})

    whole = jsonschema.Draft202012Validator(schema)
    fence = re.compile(r"^```json (request|reply|event)(?: (\w+))?\s*$")
    lines = open(docs_path, encoding="utf-8").read().split("\n")
    checked = 0
    failures = 0
    kinds = set()
    replies = set()
    events = set()
    i = 0
    while i < len(lines):
        m = fence.match(lines[i])
        if not m:
            i += 1
            continue
        start = i + 1
        kind, command = m.group(1), m.group(2)
        body = []
        i += 1
        while i < len(lines) and lines[i] != "```":
            body.append(lines[i])
            i += 1
        i += 1
        where = f"{docs_path}:{start}"
        try:
            example = json.loads("\n".join(body))
        except json.JSONDecodeError as e:
            print(f"{where}: example is not JSON: {e}")
            failures += 1
            continue
        refs = [f"#/$defs/{kind}"]
        if command:
            if f"result_{command}" not in schema["$defs"]:
                print(f"{where}: no result schema for command '{command}'")
                failures += 1
                continue
            refs.append(f"#/$defs/result_{command}")
        for ref in refs:
            target = example["result"] if ref.startswith("#/$defs/result_") else example
            errors = list(validator(ref).iter_errors(target))
            for error in errors:
                path = "/".join(str(p) for p in error.absolute_path)
                print(f"{where}: {kind} fails {ref} at '{path}': {error.message}")
            failures += 1 if errors else 0
        if not whole.is_valid(example):
            print(f"{where}: not valid against the whole schema")
            failures += 1
        if kind == "request":
            kinds.add(example.get("cmd"))
        if kind == "reply" and command:
            replies.add(command)
        if kind == "event":
            events.add(example.get("event"))
        checked += 1
    # Every request kind in the schema must have at least one example.
    for name in schema["$defs"]:
        if name.startswith("request_") and name[len("request_"):] not in kinds:
            print(f"{docs_path}: no request example for '{name[len('request_'):]}'")
            failures += 1
        if name.startswith("request_") and name[len("request_"):] not in replies:
            print(f"{docs_path}: no 'json reply {name[len('request_'):]}' example")
            failures += 1
    # Every event the schema describes must have at least one example.
    for branch in schema["$defs"]["event"].get("allOf", []):
        name = branch["if"]["properties"]["event"]["const"]
        if name not in events:
            print(f"{docs_path}: no example of the '{name}' event")
            failures += 1
    print(f"checked {checked} examples, {failures} failures")
    return 1 if failures or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
