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
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

etree = pytest.importorskip("lxml.etree")
rclpy = pytest.importorskip("rclpy")

from helpers.node_harness import LATCHED, Client, NodeProcess, wait_until  # noqa: E402
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
START_TIMEOUT_S = 60.0

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


def policy_interface(policy: etree._ElementTree) -> Interface:
    """What the ``/clew_planner`` enclave allows, by role, as fully qualified names."""
    allowed: Interface = {"publish": set(), "subscribe": set(), "reply": set(), "request": set()}
    (enclave,) = policy.getroot().findall("enclaves/enclave")
    assert enclave.get("path") == ENCLAVE
    (profile,) = enclave.findall("profiles/profile")
    assert (profile.get("ns"), profile.get("node")) == (NODE_NAMESPACE, NODE_NAME)
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
                allowed[role].add(resolve(name, NODE_NAMESPACE, NODE_NAME))
    return allowed


def dds_permissions(policy: etree._ElementTree) -> etree._ElementTree:
    """The DDS permissions document ``create_permission`` would sign, validated against ``permissions.xsd``."""
    parser = etree.XMLParser(no_network=True, resolve_entities=False)
    transform = etree.XSLT(etree.parse(str(SROS2 / "permissions.xsl"), parser))
    permissions = transform(policy, allow_ros_discovery_topic=etree.XSLT.strparam("1"))
    for domain in permissions.findall("permissions/grant/*/domains/id"):
        domain.text = "33"  # create_permission writes ROS_DOMAIN_ID here
    etree.XMLSchema(etree.parse(str(SROS2 / "permissions.xsd"), parser)).assertValid(permissions)
    return permissions


@pytest.fixture(scope="module")
def node_interface(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Interface]:
    """The publishers, subscriptions, services and clients of a running ``/clew_planner``, by role."""
    log = tmp_path_factory.mktemp("policy") / "node.log"
    node = NodeProcess(log, QUICK, {"record.enabled": False}, namespace=NODE_NAMESPACE)
    client = Client("clew_policy_probe")
    try:
        client.inbox(f"/{NODE_NAME}/world_yaml", String, LATCHED).wait_for(timeout_s=START_TIMEOUT_S)
        graph = client.node

        def listed() -> Interface:
            return {
                role: {name for name, _types in list_by_node(NODE_NAME, NODE_NAMESPACE)}
                for role, list_by_node in (
                    ("publish", graph.get_publisher_names_and_types_by_node),
                    ("subscribe", graph.get_subscriber_names_and_types_by_node),
                    ("reply", graph.get_service_names_and_types_by_node),
                    ("request", graph.get_client_names_and_types_by_node),
                )
            }

        # the latched world arrived, so the node is up; its endpoints are announced together, but wait
        # until two reads agree, so that a list read mid-discovery does not pass for the whole
        previous: list[Interface] = [listed()]

        def settled() -> bool:
            current = listed()
            same = current == previous[0]
            previous[0] = current
            return same and bool(current["reply"])

        wait_until(settled, 20.0, "the node's interface in the graph")
        yield previous[0]
    finally:
        client.close()
        assert node.stop() == 0, node.output()


def test_policy_is_valid_for_sros2() -> None:
    policy = load_policy()
    allowed = policy_interface(policy)
    assert allowed["request"] == set()  # the node calls no service
    dds_permissions(policy)


@pytest.mark.ros
def test_policy_allows_exactly_the_node_interface(node_interface: Interface) -> None:
    expected = {role: set(names) for role, names in node_interface.items()}
    if not have_tf2_msgs():
        assert not (expected["publish"] & TF_TOPICS)
        expected["publish"] |= TF_TOPICS
    allowed = policy_interface(load_policy())
    for role in ("publish", "subscribe", "reply", "request"):
        assert allowed[role] - expected[role] == set(), f"{role}: allowed but the node does not use it"
        assert expected[role] - allowed[role] == set(), f"{role}: the node uses it but the policy denies it"


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
