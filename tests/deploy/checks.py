"""Offline validators for deploy/: Kubernetes core kinds (kubernetes-validate's schemas, strict:
an unknown field is an error), the RayCluster (KubeRay's CRD schema, made strict the same
way), the compose files (the compose spec's schema, from check-jsonschema) and a reading of
compose's `${VAR:-default}` interpolation. Each returns the problems it found, '' when none,
so a test can show what a wrong field gives."""

from __future__ import annotations

import copy
import importlib.resources
import json
import re
from collections.abc import Iterable, Iterator, Mapping
from functools import cache
from pathlib import Path
from typing import Any

import jsonschema
import kubernetes_validate
import yaml
from referencing import Registry, Resource

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
DEPLOY = ROOT / "deploy"
K8S = DEPLOY / "k8s"
CRD_SCHEMA = HERE / "schemas" / "ray.io_rayclusters.v1.json"
# the oldest Kubernetes the manifests are meant for (KubeRay 1.7's floor) and the newest
# kubernetes-validate knows
K8S_VERSIONS = ("1.30", kubernetes_validate.latest_version())

Doc = dict[str, Any]


def load_docs(path: Path) -> list[Doc]:
    return [d for d in yaml.safe_load_all(path.read_text()) if d]


def describe(errors: Iterable[jsonschema.ValidationError]) -> Iterator[str]:
    """Every error as `path: message`, the alternatives of a oneOf/anyOf included."""
    for e in errors:
        where = ".".join(str(p) for p in e.absolute_path) or "(top)"
        yield f"{where}: {e.message}"
        yield from describe(e.context or ())


# --- Kubernetes core kinds -------------------------------------------------------------------


def core_problems(doc: Doc) -> str:
    """The document against its kind's schema for each Kubernetes version, strict."""
    out = []
    for version in K8S_VERSIONS:
        try:
            kubernetes_validate.validate(doc, version, strict=True)
        except kubernetes_validate.ValidationError as e:
            where = ".".join(str(p) for p in e.path) or "(top)"
            out.append(f"Kubernetes {version}: {where}: {e.message}")
    return "\n".join(out)


def is_core(doc: Doc) -> bool:
    """A kind whose schema kubernetes-validate has (the API groups of Kubernetes itself)."""
    group = str(doc.get("apiVersion", "")).rpartition("/")[0]
    return group == "" or "." not in group or group.endswith(".k8s.io")


# --- the RayCluster --------------------------------------------------------------------------

OBJECT_META = "/api/_definitions.json#/$defs/io.k8s.apimachinery.pkg.apis.meta.v1.ObjectMeta"


def strict(schema: Any) -> Any:
    """A CRD's structural schema as a JSON schema that rejects unknown fields: an object
    that lists its properties, says nothing of others and does not keep unknown fields
    (x-kubernetes-preserve-unknown-fields) gets additionalProperties: false, as the API
    server's strict field validation (kubectl apply's default) refuses such a field."""
    if isinstance(schema, list):
        return [strict(s) for s in schema]
    if not isinstance(schema, dict):
        return schema
    out = {k: strict(v) if k != "properties" else v for k, v in schema.items()}
    if "properties" in schema:
        out["properties"] = {k: strict(v) for k, v in schema["properties"].items()}
        if "additionalProperties" not in schema and not schema.get(
            "x-kubernetes-preserve-unknown-fields"
        ):
            out["additionalProperties"] = False
    return out


@cache
def raycluster_validator() -> jsonschema.Draft202012Validator:
    """KubeRay's RayCluster v1 schema, strict; its metadata as Kubernetes' ObjectMeta (the
    CRD leaves the top-level metadata to the API server), apiVersion and kind fixed."""
    schema = strict(json.loads(CRD_SCHEMA.read_text()))
    schema = copy.deepcopy(schema)
    schema["$id"] = "https://kubernetes.io/crd/ray.io/raycluster-v1.json"
    schema["properties"]["metadata"] = {"$ref": OBJECT_META}
    schema["properties"]["apiVersion"] = {"const": "ray.io/v1"}
    schema["properties"]["kind"] = {"const": "RayCluster"}
    schema["required"] = ["apiVersion", "kind", "metadata", "spec"]
    pkg = importlib.resources.files("kubernetes_validate") / "kubernetes-json-schema"
    version = kubernetes_validate.latest_version()
    defs = json.loads((pkg / f"v{version}-local-strict" / "_definitions.json").read_text())
    registry: Registry[Any] = Resource.from_contents(defs) @ Registry()
    return jsonschema.Draft202012Validator(schema, registry=registry)


def raycluster_problems(doc: Doc) -> str:
    return "\n".join(describe(raycluster_validator().iter_errors(doc)))


def manifest_problems(doc: Doc) -> str:
    """A Kubernetes document by the schema of its kind; a kind none knows is a problem."""
    if doc.get("apiVersion") == "ray.io/v1" and doc.get("kind") == "RayCluster":
        return raycluster_problems(doc)
    if is_core(doc):
        return core_problems(doc)
    return f"no schema for {doc.get('apiVersion')} {doc.get('kind')}"


# --- compose ---------------------------------------------------------------------------------


@cache
def compose_validator() -> jsonschema.Draft202012Validator:
    text = (
        importlib.resources.files("check_jsonschema.builtin_schemas.vendor") / "compose-spec.json"
    ).read_text()
    schema = json.loads(text)
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def compose_problems(doc: Doc) -> str:
    return "\n".join(describe(compose_validator().iter_errors(doc)))


_VAR = re.compile(r"\$(?:\$|\{([A-Za-z_][A-Za-z0-9_]*)(?:(:?[-?])([^}]*))?\}|([A-Za-z_]\w*))")


def interpolate(value: Any, env: Mapping[str, str], unset: list[str] | None = None) -> Any:
    """Compose's interpolation of `$VAR`, `${VAR}`, `${VAR:-default}`, `${VAR-default}`
    and `$$` in every string of a document; variables used without a default are noted."""
    if isinstance(value, dict):
        return {k: interpolate(v, env, unset) for k, v in value.items()}
    if isinstance(value, list):
        return [interpolate(v, env, unset) for v in value]
    if not isinstance(value, str):
        return value

    def one(m: re.Match[str]) -> str:
        if m.group(0) == "$$":
            return "$"
        name = m.group(1) or m.group(4)
        op, default = m.group(2), m.group(3)
        if op is None:
            if unset is not None and name not in env:
                unset.append(name)
            return env.get(name, "")
        if op in (":?", "?"):
            raise AssertionError(f"${{{name}}} is required")
        given = env.get(name)
        if given is None or (op == ":-" and given == ""):
            return default or ""
        return given

    return _VAR.sub(one, value)


def merge(base: Any, override: Any) -> Any:
    """Compose's merge of an override file for what ours use: mappings merged key by key,
    anything else replaced."""
    if isinstance(base, dict) and isinstance(override, dict):
        out = dict(base)
        for k, v in override.items():
            out[k] = merge(base[k], v) if k in base else v
        return out
    return override


def environment(service: Doc) -> dict[str, str]:
    env = service.get("environment", {})
    if isinstance(env, list):
        env = dict(e.split("=", 1) for e in env)
    return {k: str(v) for k, v in env.items()}


def env_file(path: Path) -> dict[str, str]:
    """KEY=VALUE lines (a kustomize env file, a systemd EnvironmentFile= as systemd reads it):
    comments and blanks skipped, a value's surrounding quotes dropped."""
    out = {}
    for line in path.read_text().splitlines():
        line = line.strip()
        if line and not line.startswith(("#", ";")):
            key, value = line.split("=", 1)
            out[key.strip()] = value.strip().strip('"')
    return out
