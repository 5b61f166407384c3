//! rmw_zenoh's conventions, as far as a publisher needs them (rmw_zenoh's `docs/design.md`;
//! the format is the one ROS 2 Jazzy and later speak):
//!
//! - **Data:** a topic's messages are put on `<domain_id>/<topic>/<type>/<type_hash>`, the topic
//!   being its fully qualified name without the leading slash (inner slashes kept), the type its
//!   DDS-mangled name: `0/odom/nav_msgs::msg::dds_::Odometry_/RIHS01_3cc9…`.
//! - **Attachment:** each put carries, serialized with Zenoh's own serializer (`zenoh-ext`), the
//!   publisher's sequence number (i64, from 1), the source timestamp (i64, ns since the Unix
//!   epoch) and its 16-byte GID (an array: a length 16 as a varint, then the bytes).
//! - **Discovery:** liveliness tokens, held while the entity lives, under `@ros2_lv`:
//!   `@ros2_lv/<domain>/<zid>/<node_id>/<node_id>/NN/<enclave>/<namespace>/<node>` for the node,
//!   `@ros2_lv/<domain>/<zid>/<node_id>/<entity_id>/MP/<enclave>/<namespace>/<node>/<topic>/<type>/<type_hash>/<qos>`
//!   for a publisher (`SS` for a service server), with every `/` inside a name written `%` and an
//!   empty name as `%`. That is what `ros2 topic list`, `ros2 service list` and `ros2 node list`
//!   read.
//! - **Services:** a queryable on `<domain_id>/<service>/<pkg>::srv::dds_::<Name>_/<type_hash>`;
//!   the reply carries the request's sequence number and the client's GID (see `services`).

use zenoh::bytes::ZBytes;
use zenoh_ext::ZSerializer;

use crate::msgs::MsgType;

/// QoS in a liveliness token: the default profile (reliable, volatile, keep last) at depth 10,
/// every other policy default (`<reliability>:<durability>:<history>,<depth>:<deadline s,ns>:
/// <lifespan s,ns>:<liveliness kind,s,ns>`, an empty field meaning "the default").
pub const QOS_DEFAULT_DEPTH_10: &str = "::,10:,:,:,,";

/// Writes a name for a liveliness token: every `/` as `%`, and an empty name as `%`.
pub fn mangle(name: &str) -> String {
    if name.is_empty() {
        "%".into()
    } else {
        name.replace('/', "%")
    }
}

/// One ROS 2 node as rmw_zenoh names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeName {
    pub domain_id: u32,
    /// `""` (the root) or `/a/b`.
    pub namespace: String,
    pub name: String,
}

impl NodeName {
    /// The fully qualified name of `topic`: itself when absolute, else under the namespace.
    pub fn resolve(&self, topic: &str) -> String {
        if topic.starts_with('/') {
            topic.to_string()
        } else {
            format!("{}/{topic}", self.namespace.trim_end_matches('/'))
        }
    }

    /// The node's liveliness token.
    pub fn node_token(&self, zid: &str, node_id: u64) -> String {
        // A root namespace ("" or "/") is written "%", as rmw_zenoh does.
        let ns = if self.namespace == "/" { "" } else { &self.namespace };
        format!("@ros2_lv/{}/{zid}/{node_id}/{node_id}/NN/%/{}/{}", self.domain_id, mangle(ns), mangle(&self.name))
    }

    /// A publisher's liveliness token.
    pub fn publisher_token(&self, zid: &str, node_id: u64, entity_id: u64, fq_topic: &str, ty: MsgType) -> String {
        self.entity_token(zid, node_id, entity_id, "MP", fq_topic, &ty.dds_name(), ty.type_hash())
    }

    /// A subscription's liveliness token (`MS`): what makes `ros2 topic info` count it.
    pub fn subscription_token(&self, zid: &str, node_id: u64, entity_id: u64, fq_topic: &str, ty: MsgType) -> String {
        self.entity_token(zid, node_id, entity_id, "MS", fq_topic, &ty.dds_name(), ty.type_hash())
    }

    /// An entity's liveliness token: `kind` is `MP` (publisher), `SS` (service server), …; the
    /// services' default QoS is the topics' (reliable, volatile, keep last 10).
    #[allow(clippy::too_many_arguments)]
    pub fn entity_token(
        &self,
        zid: &str,
        node_id: u64,
        entity_id: u64,
        kind: &str,
        fq_name: &str,
        dds_type: &str,
        type_hash: &str,
    ) -> String {
        let ns = if self.namespace == "/" { "" } else { &self.namespace };
        format!(
            "@ros2_lv/{}/{zid}/{node_id}/{entity_id}/{kind}/%/{}/{}/{}/{}/{type_hash}/{QOS_DEFAULT_DEPTH_10}",
            self.domain_id,
            mangle(ns),
            mangle(&self.name),
            mangle(fq_name),
            mangle(dds_type),
        )
    }

    /// The key expression a topic's messages are put on.
    pub fn topic_key(&self, fq_topic: &str, ty: MsgType) -> String {
        self.service_key(fq_topic, &ty.dds_name(), ty.type_hash())
    }

    /// The key expression of a topic or a service: `<domain>/<name>/<type>/<hash>`.
    pub fn service_key(&self, fq_name: &str, dds_type: &str, type_hash: &str) -> String {
        let name = fq_name.trim_start_matches('/').trim_end_matches('/');
        format!("{}/{name}/{dds_type}/{type_hash}", self.domain_id)
    }
}

/// An entity's GID, as rmw_zenoh makes it (`generate_gid` in `liveliness_utils.cpp`): the
/// XXH3 128-bit hash of its liveliness token's key, its low 64 bits then its high 64 bits, each
/// in the machine's (little-endian) byte order. A ROS 2 subscriber compares it with the GID of
/// the publisher it discovered through that token, so it must be this hash and no other.
pub fn gid(token: &str) -> [u8; 16] {
    xxhash_rust::xxh3::xxh3_128(token.as_bytes()).to_le_bytes()
}

/// The attachment of one put: sequence number, source timestamp (ns since the epoch), GID.
pub fn attachment(sequence_number: i64, source_timestamp_ns: i64, gid: &[u8; 16]) -> ZBytes {
    let mut s = ZSerializer::new();
    s.serialize(sequence_number);
    s.serialize(source_timestamp_ns);
    s.serialize(gid);
    s.finish()
}

/// Whether `name` is a valid ROS 2 name token run (`a`, `a/b`, `/a/b_c`): letters, digits and
/// underscores, segments that do not start with a digit, no empty segment, no trailing slash.
pub fn valid_ros_name(name: &str, absolute_allowed: bool) -> bool {
    let body = match name.strip_prefix('/') {
        Some(rest) if absolute_allowed => rest,
        Some(_) => return false,
        None => name,
    };
    !body.is_empty()
        && body.split('/').all(|seg| {
            !seg.is_empty()
                && !seg.starts_with(|c: char| c.is_ascii_digit())
                && seg.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !seg.contains("__")
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn node(ns: &str) -> NodeName {
        NodeName { domain_id: 7, namespace: ns.into(), name: "situate".into() }
    }

    #[test]
    fn topic_keys_keep_inner_slashes_and_drop_the_leading_one() {
        let n = node("/robot1");
        assert_eq!(n.resolve("odom"), "/robot1/odom");
        assert_eq!(n.resolve("/odom"), "/odom");
        assert_eq!(node("").resolve("odom"), "/odom");
        assert_eq!(
            n.topic_key("/robot1/odom", MsgType::Odometry),
            format!("7/robot1/odom/nav_msgs::msg::dds_::Odometry_/{}", MsgType::Odometry.type_hash())
        );
    }

    #[test]
    fn tokens_mangle_slashes_and_write_empty_names_as_percent() {
        let zid = "1234abcd";
        assert_eq!(node("").node_token(zid, 0), "@ros2_lv/7/1234abcd/0/0/NN/%/%/situate");
        assert_eq!(node("/r/s").node_token(zid, 3), "@ros2_lv/7/1234abcd/3/3/NN/%/%r%s/situate");
        assert_eq!(
            node("").publisher_token(zid, 0, 2, "/cmd_vel", MsgType::Twist),
            format!(
                "@ros2_lv/7/1234abcd/0/2/MP/%/%/situate/%cmd_vel/geometry_msgs::msg::dds_::Twist_/{}/::,10:,:,:,,",
                MsgType::Twist.type_hash()
            )
        );
    }

    #[test]
    fn the_attachment_is_two_i64_then_a_16_byte_array() {
        let g = gid("@ros2_lv/0/x");
        assert_ne!(g, gid("@ros2_lv/0/y"));
        let bytes = attachment(3, 1_700_000_000_000_000_000, &g).to_bytes().into_owned();
        assert_eq!(bytes.len(), 8 + 8 + 1 + 16);
        assert_eq!(&bytes[..8], &3i64.to_le_bytes());
        assert_eq!(&bytes[8..16], &1_700_000_000_000_000_000i64.to_le_bytes());
        assert_eq!(bytes[16], 16, "the array's length, as a varint");
        assert_eq!(&bytes[17..], &g);
    }

    #[test]
    fn the_gid_is_xxh3_128_low_half_first() {
        // XXH3-128 of no bytes is 99aa06d3014798d8_6001c324468d497f (xxHash's own test vector).
        let mut expected = [0u8; 16];
        expected[..8].copy_from_slice(&0x6001_c324_468d_497f_u64.to_le_bytes());
        expected[8..].copy_from_slice(&0x99aa_06d3_0147_98d8_u64.to_le_bytes());
        assert_eq!(gid(""), expected);
    }

    #[test]
    fn ros_names() {
        for ok in ["odom", "cmd_vel", "a/b", "sonar_ring2"] {
            assert!(valid_ros_name(ok, true), "{ok}");
        }
        assert!(valid_ros_name("/odom", true));
        assert!(!valid_ros_name("/odom", false));
        for bad in ["", "/", "a//b", "a/", "2d", "a-b", "a b", "a__b", "~/x", "sonar.range"] {
            assert!(!valid_ros_name(bad, true), "{bad}");
        }
    }
}
