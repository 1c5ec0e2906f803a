#!/usr/bin/env python3
"""Validates the manifests here against the Kubernetes Job schema, as far as it can be had
without a cluster: the models of the official Python client (`pip install kubernetes pyyaml`),
which are generated from the Kubernetes OpenAPI schema.

Checks, recursively: every key is a field of its object (no typos: the client itself would drop
them silently), every value has the field's type, every required field is there (the models'
own client-side validation), and apiVersion/kind are batch/v1 Job.

    python3 contrib/k8s/validate.py contrib/k8s/*.yaml
"""
import datetime
import re
import sys

import kubernetes
import kubernetes.client as k8s
import yaml

PRIMITIVES = {
    "str": str,
    "int": int,
    "float": (int, float),
    "bool": bool,
    "object": object,
    "datetime": (str, datetime.datetime),
    "date": (str, datetime.date),
}


def check(value, type_name, where, errors):
    """Checks `value` against the client's type name (`V1Job`, `list[V1Container]`, …)."""
    m = re.fullmatch(r"(?:list|List)\[(.*)\]", type_name)
    if m:
        if not isinstance(value, list):
            errors.append(f"{where}: expected a list, got {type(value).__name__}")
            return
        for i, v in enumerate(value):
            check(v, m.group(1), f"{where}[{i}]", errors)
        return
    m = re.fullmatch(r"(?:dict\((.*), (.*)\)|Dict\[(.*?), (.*)\])", type_name)
    if m:
        if not isinstance(value, dict):
            errors.append(f"{where}: expected a map, got {type(value).__name__}")
            return
        for k, v in value.items():
            check(v, m.group(2) or m.group(4), f"{where}.{k}", errors)
        return
    if type_name in PRIMITIVES:
        # YAML ints are valid where the schema says int-or-string (str in the client).
        ok = isinstance(value, PRIMITIVES[type_name]) or (
            type_name == "str" and isinstance(value, (int, float))
        )
        if not ok or (type_name == "int" and isinstance(value, bool)):
            errors.append(f"{where}: expected {type_name}, got {value!r}")
        return
    cls = getattr(k8s, type_name)
    if not isinstance(value, dict):
        errors.append(f"{where}: expected a {type_name} object, got {value!r}")
        return
    by_json = {json: attr for attr, json in cls.attribute_map.items()}
    for key, v in value.items():
        if key not in by_json:
            errors.append(f"{where}.{key}: not a field of {type_name}")
            continue
        check(v, cls.openapi_types[by_json[key]], f"{where}.{key}", errors)


def required(doc, errors):
    """Required fields and value types, by the client's own model validation (pydantic in
    recent clients, setters in older ones)."""
    try:
        if hasattr(k8s.V1Job, "from_dict"):
            k8s.V1Job.from_dict(doc)
        else:
            k8s.ApiClient()._ApiClient__deserialize(doc, "V1Job")
    except (ValueError, TypeError) as e:
        errors.append(" ".join(str(e).split()))


def main(paths):
    failed = False
    for path in paths:
        with open(path) as f:
            docs = [d for d in yaml.safe_load_all(f) if d is not None]
        for doc in docs:
            errors = []
            if (doc.get("apiVersion"), doc.get("kind")) != ("batch/v1", "Job"):
                errors.append(f"expected apiVersion batch/v1, kind Job, got {doc.get('apiVersion')} {doc.get('kind')}")
            check(doc, "V1Job", "Job", errors)
            required(doc, errors)
            name = doc.get("metadata", {}).get("name")
            for e in errors:
                print(f"{path}: {e}", file=sys.stderr)
            if errors:
                failed = True
            else:
                print(f"{path}: Job {name} is valid against the V1Job schema of the Kubernetes Python client {kubernetes.__version__}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
