"""The shipped SROS2 policy allows exactly what clew_planner uses (issue 42).

``config/sros2/clew_planner_policy.xml`` is read as ``ros2 security
create_permission`` reads it: validated against sros2's ``policy.xsd``, then
turned into a DDS permissions document by sros2's ``permissions.xsl`` and
validated against ``permissions.xsd`` (test/data/sros2/, copied from sros2
0.13.0). A real ``clew_planner`` (the node ``/clew_planner``, as deployed)
is started in a subprocess, and a node in this process lists its
publishers, subscriptions, services and clients through the ROS graph (the
calls ``ros2 security generate_policy`` makes): the policy's names, and the
DDS topics of the permissions, must equal that list, no more and no less.
``/tf`` and ``/tf_static`` are published where ``tf2_msgs`` is installed (a
native install; not the PyPI wheels), so they count as published there.
The other enclaves of the robot's graph (``config/sros2/clew_clients_policy.xml``: the operator, the
controller, the live state's publishers) are restricted too: valid for sros2, deny by default, and none may
publish what the planner publishes, serve its services or change its parameters.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from copy import deepcopy
from pathlib import Path

import pytest

etree = pytest.importorskip("lxml.etree")
rclpy = pytest.importorskip("rclpy")

from helpers.node_harness import LATCHED, Client, NodeProcess, PlannersProcess, wait_until  # noqa: E402
from rclpy.node import NodeNameNonExistentError  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from clew_ros.node.publishing import have_tf2_msgs  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
POLICY = ROOT / "config" / "sros2" / "clew_planner_policy.xml"
SROS2 = ROOT / "test" / "data" / "sros2"
QUICK = ROOT / "test" / "worlds" / "node_quick.yaml"
ENCLAVE = "/clew_planner"
NODE_NAMESPACE, NODE_NAME = "/", "clew_planner"
#: Published only where tf2_msgs is installed (clew_ros.node.publishing.have_tf2_msgs).
TF_TOPICS = {"/tf", "/tf_static"}
#: What ``create_permission`` adds for rmw_fastrtps_cpp (sros2's _RMW_WITH_ROS_GRAPH_INFO_TOPIC).
DISCOVERY_TOPIC = "ros_discovery_info"
#: How long the node may take to start (s): a cold numba cache compiles first (over 60 s on a loaded machine).
START_TIMEOUT_S = 180.0
#: Time between two reads of the graph that must agree (s): endpoint announcements come within ms of each other.
SETTLE_S = 1.0

Interface = dict[str, set[str]]  # role (publish, subscribe, reply, request) -> fully qualified names


def load_policy() -> etree._ElementTree:
    """The policy, validated as sros2's ``load_policy`` does (XInclude, then ``policy.xsd``)."""
    parser = etree.XMLParser(no_network=True, resolve_entities=False)
    policy = etree.parse(str(POLICY), parser)
    policy.xinclude()
    schema = etree.XMLSchema(etree.parse(str(SROS2 / "policy.xsd"), parser))
    schema.assertValid(policy)
    return policy


def resolve(name: str, namespace: str, node: str) -> str:
    """A policy name made fully qualified, as sros2's ``permissions.xsl`` does (``~``: under the node)."""
    prefix = namespace if namespace.endswith("/") else namespace + "/"
    if name.startswith("/"):
        return name
    if name.startswith("~"):
        return prefix + node + name[1:]
    return prefix + name


def the_profile(policy: etree._ElementTree) -> etree._Element:
    """The one profile of the one enclave, ``/clew_planner``, of the policy."""
    (enclave,) = policy.getroot().findall("enclaves/enclave")
    assert enclave.get("path") == ENCLAVE
    (profile,) = enclave.findall("profiles/profile")
    assert (profile.get("ns"), profile.get("node")) == (NODE_NAMESPACE, NODE_NAME)
    return profile


def policy_interface(profile: etree._Element) -> Interface:
    """What a profile allows, by role, as fully qualified names."""
    allowed: Interface = {"publish": set(), "subscribe": set(), "reply": set(), "request": set()}
    for rules in profile:
        if not isinstance(rules.tag, str):  # a comment
            continue
        assert rules.tag in ("topics", "services"), f"unexpected <{rules.tag}> in the profile"
        roles = {key: value for key, value in rules.attrib.items() if key in allowed}
        assert set(roles.values()) == {"ALLOW"}, f"<{rules.tag} {rules.attrib}>: only ALLOW rules, default DENY"
        for entry in rules:
            if not isinstance(entry.tag, str):
                continue
            name = (entry.text or "").strip()
            assert not set(name) & set("*?[]"), f"{name}: a wildcard allows more than the node has"
            for role in roles:
                allowed[role].add(resolve(name, profile.get("ns"), profile.get("node")))
    return allowed


def namespaced_profile(profile: etree._Element, namespace: str) -> etree._Element:
    """The profile of a planner in ``namespace``, as docs/security.md says to write it: ``ns`` set, and
    ``tf`` / ``tf_static`` relative (clew_planners and its launch file remap them into the namespace)."""
    copy = deepcopy(profile)
    copy.set("ns", namespace)
    for topic in copy.iter("topic"):
        if topic.text in TF_TOPICS:
            topic.text = topic.text.lstrip("/")
    return copy


def dds_permissions(policy: etree._ElementTree) -> etree._ElementTree:
    """The DDS permissions document ``create_permission`` would sign, validated against ``permissions.xsd``."""
    parser = etree.XMLParser(no_network=True, resolve_entities=False)
    transform = etree.XSLT(etree.parse(str(SROS2 / "permissions.xsl"), parser))
    permissions = transform(policy, allow_ros_discovery_topic=etree.XSLT.strparam("1"))
    for domain in permissions.findall("permissions/grant/*/domains/id"):
        domain.text = "33"  # create_permission writes ROS_DOMAIN_ID here
    etree.XMLSchema(etree.parse(str(SROS2 / "permissions.xsd"), parser)).assertValid(permissions)
    return permissions


def graph_interface(client: Client, namespace: str, node: str) -> Interface:
    """The publishers, subscriptions, services and clients of ``namespace/node`` in the ROS graph, by role,
    once two reads :data:`SETTLE_S` apart agree. The node creates every endpoint before it publishes its world,
    but discovery announces them one by one, so a list read just after the world arrived may lack the last
    ones; the node creates nothing later, so a list that stays the same is the whole."""
    graph = client.node

    def listed() -> Interface:
        try:
            return {
                role: {name for name, _types in list_by_node(node, namespace)}
                for role, list_by_node in (
                    ("publish", graph.get_publisher_names_and_types_by_node),
                    ("subscribe", graph.get_subscriber_names_and_types_by_node),
                    ("reply", graph.get_service_names_and_types_by_node),
                    ("request", graph.get_client_names_and_types_by_node),
                )
            }
        except NodeNameNonExistentError:  # its topics may arrive before its name (ros_discovery_info)
            return {}

    previous: list[Interface] = [listed()]

    def settled() -> bool:
        time.sleep(SETTLE_S)
        current = listed()
        same = current == previous[0]
        previous[0] = current
        return same and bool(current.get("reply"))

    wait_until(settled, 20.0, f"the interface of {namespace}/{node} in the graph")
    return previous[0]


def with_tf(interface: Interface, tf_topics: set[str]) -> Interface:
    """``interface`` with ``tf_topics`` published where tf2_msgs is missing (a native install publishes them)."""
    expected = {role: set(names) for role, names in interface.items()}
    if not have_tf2_msgs():
        assert not (expected["publish"] & tf_topics)
        expected["publish"] |= tf_topics
    return expected


def assert_same(allowed: Interface, expected: Interface) -> None:
    for role in ("publish", "subscribe", "reply", "request"):
        assert allowed[role] - expected[role] == set(), f"{role}: allowed but the node does not use it"
        assert expected[role] - allowed[role] == set(), f"{role}: the node uses it but the policy denies it"


@pytest.fixture(scope="module")
def node_interface(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Interface]:
    """The interface of a running ``/clew_planner``, by role."""
    log = tmp_path_factory.mktemp("policy") / "node.log"
    node = NodeProcess(log, QUICK, {"record.enabled": False}, namespace=NODE_NAMESPACE)
    client = Client("clew_policy_probe")
    try:
        # the latched world arrived: the node is up
        client.inbox(f"/{NODE_NAME}/world_yaml", String, LATCHED).wait_for(timeout_s=START_TIMEOUT_S)
        yield graph_interface(client, NODE_NAMESPACE, NODE_NAME)
    finally:
        client.close()
        assert node.stop() == 0, node.output()


def test_policy_is_valid_for_sros2() -> None:
    policy = load_policy()
    allowed = policy_interface(the_profile(policy))
    assert allowed["request"] == set()  # the node calls no service
    dds_permissions(policy)


@pytest.mark.ros
def test_policy_allows_exactly_the_node_interface(node_interface: Interface) -> None:
    assert_same(policy_interface(the_profile(load_policy())), with_tf(node_interface, TF_TOPICS))


@pytest.mark.ros
def test_namespaced_profiles_allow_exactly_each_planner_interface(tmp_path: Path) -> None:
    """docs/security.md's variant for several planners: the profile with ``ns`` set and ``tf`` relative
    allows exactly what each planner of ``clew_planners`` uses."""
    namespaces = ("/arm_a", "/robots/arm_b")
    process = PlannersProcess(
        tmp_path / "planners.log",
        dict.fromkeys(namespaces, QUICK),
        ["-p", "record.enabled:=false"],
    )
    client = Client("clew_policy_probe")
    try:
        profile = the_profile(load_policy())
        for namespace in namespaces:
            client.inbox(f"{namespace}/{NODE_NAME}/world_yaml", String, LATCHED).wait_for(timeout_s=START_TIMEOUT_S)
            interface = graph_interface(client, namespace, NODE_NAME)
            allowed = policy_interface(namespaced_profile(profile, namespace))
            assert_same(allowed, with_tf(interface, {f"{namespace}/tf", f"{namespace}/tf_static"}))
    finally:
        client.close()
        assert process.stop() == 0, process.output()


@pytest.mark.ros
def test_dds_permissions_name_exactly_the_node_topics(node_interface: Interface) -> None:
    """The permissions' DDS topic names equal the node's names as rmw_fastrtps mangles them."""
    published = set(node_interface["publish"]) | (set() if have_tf2_msgs() else TF_TOPICS)
    expected_publish = (
        {f"rt{name}" for name in published} | {f"rr{name}Reply" for name in node_interface["reply"]} | {DISCOVERY_TOPIC}
    )
    expected_subscribe = (
        {f"rt{name}" for name in node_interface["subscribe"]}
        | {f"rq{name}Request" for name in node_interface["reply"]}
        | {DISCOVERY_TOPIC}
    )
    permissions = dds_permissions(load_policy())
    (grant,) = permissions.findall("permissions/grant")
    assert grant.get("name") == ENCLAVE
    assert grant.findtext("subject_name") == f"CN={ENCLAVE}"
    assert grant.findtext("default") == "DENY"
    assert grant.findall("deny_rule") == []
    publish = {t.text for t in grant.findall("allow_rule/publish/topics/topic")}
    subscribe = {t.text for t in grant.findall("allow_rule/subscribe/topics/topic")}
    assert publish == expected_publish
    assert subscribe == expected_subscribe


# --------------------------------------------------------------------------- the other enclaves

CLIENTS = ROOT / "config" / "sros2" / "clew_clients_policy.xml"
#: What each client enclave may do to the planner beyond reading it: publish these of its topics.
CLIENT_INPUTS = {
    "/clew_operator": {"/clew_planner/goal_pose"},
    "/clew_controller": set(),
    "/clew_state": {"/clew_planner/object", "/clew_planner/obstacles", "/clew_planner/points", "/joint_states"},
}
#: The planner's services a client may call (never a parameter change).
CLIENT_CALLS = {
    "/clew_operator": {
        "/clew_planner/plan",
        "/clew_planner/cancel",
        "/clew_planner/get_parameters",
        "/clew_planner/list_parameters",
        "/clew_planner/describe_parameters",
        "/clew_planner/get_parameter_types",
    },
    "/clew_controller": set(),
    "/clew_state": set(),
}


def load_clients() -> etree._ElementTree:
    parser = etree.XMLParser(no_network=True, resolve_entities=False)
    policy = etree.parse(str(CLIENTS), parser)
    etree.XMLSchema(etree.parse(str(SROS2 / "policy.xsd"), parser)).assertValid(policy)
    return policy


def client_interfaces(policy: etree._ElementTree) -> dict[str, Interface]:
    """Each enclave's allowed interface (its one profile's), by enclave path."""
    out = {}
    for enclave in policy.getroot().findall("enclaves/enclave"):
        (profile,) = enclave.findall("profiles/profile")
        out[enclave.get("path")] = policy_interface(profile)
    return out


def test_the_client_enclaves_are_valid_for_sros2_and_deny_by_default() -> None:
    permissions = dds_permissions(load_clients())
    grants = permissions.findall("permissions/grant")
    assert {g.get("name") for g in grants} == set(CLIENT_INPUTS)
    for grant in grants:
        assert grant.findtext("default") == "DENY"
        assert grant.findall("deny_rule") == []


def test_no_other_enclave_speaks_for_the_planner() -> None:
    """No client enclave may publish what the planner publishes (its trajectory, its frames), serve its
    services, or call its parameter changes; each publishes of the planner's topics only its inputs."""
    planner = policy_interface(the_profile(load_policy()))
    own_services = {f"/{NODE_NAME}/{name}" for name in ("set_parameters", "set_parameters_atomically")}
    shared = {"/rosout", "/parameter_events"}  # every node publishes its log and parameter changes there
    for path, allowed in client_interfaces(load_clients()).items():
        assert not (allowed["publish"] & (planner["publish"] - shared)), path
        assert not (allowed["reply"] & planner["reply"]), path
        assert not (allowed["request"] & own_services), path
        assert allowed["request"] == CLIENT_CALLS[path], path
        assert allowed["publish"] - shared == CLIENT_INPUTS[path], path
        assert {name for name in allowed["subscribe"] if not name.startswith(("/clew_planner/", "/tf"))} == set()
    assert set(client_interfaces(load_clients())).isdisjoint({ENCLAVE})
