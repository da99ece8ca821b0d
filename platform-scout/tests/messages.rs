//! CDR round trips of every message type (both byte orders), byte-level
//! layout checks against hand-computed CDR, a differential check against
//! RustDDS's own serializer (the bytes a ROS 2 node sends), and property
//! tests on random messages.

use proptest::prelude::*;
use rustdds::RepresentationIdentifier;
use rustdds::serialization::{deserialize_from_cdr_with_rep_id, to_writer_with_rep_id};
use serde::Serialize;
use serde::de::DeserializeOwned;
use sornav_platform_scout::cdr::{CdrError, Endianness, decode, decode_exact, encode};
use sornav_platform_scout::msg::*;

fn header() -> Header {
    Header::new(
        Time {
            sec: 1_700_000_000,
            nanosec: 123_456_789,
        },
        "map",
    )
}

fn cov(seed: f64) -> [f64; 36] {
    std::array::from_fn(|i| seed + i as f64)
}

fn marker() -> Marker {
    Marker {
        header: header(),
        ns: "objects".into(),
        id: 7,
        r#type: Marker::CUBE_LIST,
        action: Marker::ADD,
        pose: Pose {
            position: Point::new(1.0, 2.0, 3.0),
            orientation: Quaternion::from_yaw(0.3),
        },
        scale: Vector3::new(0.1, 0.2, 0.3),
        color: ColorRGBA {
            r: 0.1,
            g: 0.2,
            b: 0.3,
            a: 0.4,
        },
        lifetime: RosDuration { sec: 2, nanosec: 5 },
        frame_locked: true,
        points: vec![Point::new(1.0, 1.0, 1.0), Point::new(-2.0, 0.5, 0.0)],
        colors: vec![ColorRGBA::rgb(1.0, 0.0, 0.0)],
        texture_resource: "embedded://t".into(),
        texture: CompressedImage {
            header: header(),
            format: "png".into(),
            data: vec![1, 2, 3],
        },
        uv_coordinates: vec![UvCoordinate { u: 0.5, v: 0.25 }],
        text: "tv".into(),
        mesh_resource: String::new(),
        mesh_file: MeshFile {
            filename: "m.stl".into(),
            data: vec![9; 5],
        },
        mesh_use_embedded_materials: true,
    }
}

/// Round trip in both byte orders, and the same body bytes as RustDDS.
fn check<T: Serialize + DeserializeOwned + PartialEq + std::fmt::Debug>(value: &T) {
    for (e, rep) in [
        (Endianness::Little, RepresentationIdentifier::CDR_LE),
        (Endianness::Big, RepresentationIdentifier::CDR_BE),
    ] {
        let bytes = encode(value, e).unwrap();
        assert_eq!(&bytes[..2], &e.identifier());
        assert_eq!(bytes.len() % 4, 0, "padded to 4 bytes");
        assert_eq!(
            usize::from(bytes[3] & 3),
            (4 - (bytes.len() - 4 - usize::from(bytes[3] & 3)) % 4) % 4
        );
        let back: T = decode(&bytes).unwrap();
        assert_eq!(&back, value);
        let mut rustdds_body = Vec::new();
        to_writer_with_rep_id(&mut rustdds_body, value, rep).unwrap();
        let pad = usize::from(bytes[3] & 3);
        assert_eq!(
            &bytes[4..bytes.len() - pad],
            &rustdds_body[..],
            "same bytes as RustDDS"
        );
        let (from_rustdds, _) = deserialize_from_cdr_with_rep_id::<T>(&bytes[4..], rep).unwrap();
        assert_eq!(&from_rustdds, value);
    }
}

#[test]
fn every_message_type_round_trips() {
    check(&Time {
        sec: -5,
        nanosec: 999_999_999,
    });
    check(&RosDuration { sec: 3, nanosec: 4 });
    check(&header());
    check(&RosString {
        data: "find the television".into(),
    });
    check(&RosString {
        data: String::new(),
    });
    check(&Bool { data: true });
    check(&Int8 { data: -2 });
    check(&Float32 { data: 0.75 });
    check(&ColorRGBA::rgb(0.5, 0.25, 1.0));
    check(&Point::new(1.5, -2.5, 3.25));
    check(&Point32 {
        x: 1.0,
        y: 2.0,
        z: 3.0,
    });
    check(&Vector3::new(0.1, 0.2, 0.3));
    check(&Quaternion::from_yaw(1.0));
    check(&Pose {
        position: Point::new(1.0, 2.0, 3.0),
        orientation: Quaternion::from_yaw(-0.5),
    });
    check(&PoseStamped {
        header: header(),
        pose: Pose::default(),
    });
    check(&PoseWithCovariance {
        pose: Pose::default(),
        covariance: cov(0.5),
    });
    check(&Twist {
        linear: Vector3::new(0.4, 0.0, 0.0),
        angular: Vector3::new(0.0, 0.0, 0.3),
    });
    check(&TwistWithCovariance {
        twist: Twist::default(),
        covariance: cov(2.0),
    });
    check(&TwistStamped {
        header: header(),
        twist: Twist {
            linear: Vector3::new(1.0, 0.0, 0.0),
            angular: Vector3::default(),
        },
    });
    check(&PointStamped {
        header: header(),
        point: Point::new(4.0, 5.0, 0.0),
    });
    check(&Polygon {
        points: vec![
            Point32 {
                x: 0.3,
                y: 0.3,
                z: 0.0,
            },
            Point32 {
                x: -0.3,
                y: 0.3,
                z: 0.0,
            },
        ],
    });
    check(&PolygonStamped {
        header: header(),
        polygon: Polygon::default(),
    });
    check(&Odometry {
        header: header(),
        child_frame_id: "sensor".into(),
        pose: PoseWithCovariance {
            pose: Pose {
                position: Point::new(1.0, 2.0, 0.55),
                orientation: Quaternion::from_yaw(0.2),
            },
            covariance: cov(1.0),
        },
        twist: TwistWithCovariance {
            twist: Twist::default(),
            covariance: cov(-1.0),
        },
    });
    check(&Path {
        header: header(),
        poses: vec![
            PoseStamped {
                header: header(),
                pose: Pose::default()
            };
            3
        ],
    });
    check(&PointField {
        name: "intensity".into(),
        offset: 16,
        datatype: 7,
        count: 1,
    });
    check(&PointCloud2 {
        header: header(),
        height: 1,
        width: 2,
        fields: vec![PointField {
            name: "x".into(),
            offset: 0,
            datatype: 7,
            count: 1,
        }],
        is_bigendian: false,
        point_step: 4,
        row_step: 8,
        data: vec![0, 0, 128, 63, 0, 0, 0, 64],
        is_dense: true,
    });
    check(&Joy {
        header: header(),
        axes: vec![0.0, 0.0, -1.0, 0.0, 1.0, 1.0, 0.0, 0.0],
        buttons: vec![0; 11],
    });
    check(&CompressedImage {
        header: header(),
        format: "jpeg".into(),
        data: vec![255, 216, 255],
    });
    check(&UvCoordinate { u: 0.1, v: 0.9 });
    check(&MeshFile {
        filename: "a.dae".into(),
        data: vec![],
    });
    check(&marker());
    check(&MarkerArray {
        markers: vec![marker(), Marker::default()],
    });
}

#[test]
fn point_stamped_layout_matches_hand_encoded_cdr() {
    // header.stamp: sec 1, nanosec 2; frame_id "map" (length 4 incl. NUL);
    // the body is then 16 bytes long, so point.x starts 8-aligned at 16.
    let msg = PointStamped {
        header: Header::new(Time { sec: 1, nanosec: 2 }, "map"),
        point: Point::new(1.0, 2.0, 3.0),
    };
    let mut expected = vec![0x00, 0x01, 0x00, 0x00];
    expected.extend_from_slice(&1i32.to_le_bytes());
    expected.extend_from_slice(&2u32.to_le_bytes());
    expected.extend_from_slice(&4u32.to_le_bytes());
    expected.extend_from_slice(b"map\0");
    for v in [1.0f64, 2.0, 3.0] {
        expected.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(encode(&msg, Endianness::Little).unwrap(), expected);
}

#[test]
fn doubles_align_to_8_bytes_from_the_start_of_the_body() {
    // frame_id "ab" -> body 8 + 4 + 3 = 15 bytes, so x needs 1 padding byte
    // to reach 16 (counted from the body, not from the 4-byte header).
    let msg = PointStamped {
        header: Header::new(Time::default(), "ab"),
        point: Point::new(7.0, 0.0, 0.0),
    };
    let bytes = encode(&msg, Endianness::Big).unwrap();
    assert_eq!(&bytes[..4], &[0, 0, 0, 0]);
    assert_eq!(bytes[4 + 15], 0, "padding byte");
    assert_eq!(&bytes[4 + 16..4 + 24], &7.0f64.to_be_bytes());
    // Joy: header (8 + 4 + "sornav\0" = 19) then a sequence length aligned to 20.
    let joy = Joy {
        header: Header::new(Time::default(), "sornav"),
        axes: vec![-1.0],
        buttons: vec![],
    };
    let b = encode(&joy, Endianness::Little).unwrap();
    assert_eq!(&b[4 + 20..4 + 24], &1u32.to_le_bytes());
    assert_eq!(&b[4 + 24..4 + 28], &(-1.0f32).to_le_bytes());
}

#[test]
fn trailing_padding_is_accepted_and_reported() {
    let msg = Int8 { data: 5 };
    let mut bytes = encode(&msg, Endianness::Little).unwrap();
    assert_eq!(bytes.len(), 8, "1 byte body padded to 4");
    assert_eq!(bytes[3], 3, "options record 3 padding bytes");
    assert_eq!(decode_exact::<Int8>(&bytes).unwrap(), (msg, 3));
    bytes.extend_from_slice(&[0; 8]);
    assert_eq!(decode::<Int8>(&bytes).unwrap(), msg);
}

#[test]
fn malformed_payloads_are_typed_errors() {
    assert_eq!(decode::<Int8>(&[0, 1]), Err(CdrError::MissingHeader(2)));
    assert_eq!(
        decode::<Int8>(&[0, 3, 0, 0, 1, 0, 0, 0]),
        Err(CdrError::UnsupportedRepresentation([0, 3]))
    );
    let bytes = encode(&PointStamped::default(), Endianness::Little).unwrap();
    assert!(matches!(
        decode::<PointStamped>(&bytes[..bytes.len() - 9]),
        Err(CdrError::Decode { .. })
    ));
    // A string length running past the end.
    let mut s = vec![0, 1, 0, 0];
    s.extend_from_slice(&1000u32.to_le_bytes());
    s.extend_from_slice(b"abc");
    assert!(matches!(
        decode::<RosString>(&s),
        Err(CdrError::Decode { .. })
    ));
}

fn arb_header() -> impl Strategy<Value = Header> {
    (any::<i32>(), 0u32..1_000_000_000, "[a-z_/]{0,12}")
        .prop_map(|(sec, nanosec, f)| Header::new(Time { sec, nanosec }, f))
}

fn arb_point() -> impl Strategy<Value = Point> {
    (-1e6f64..1e6, -1e6f64..1e6, -1e3f64..1e3).prop_map(|(x, y, z)| Point::new(x, y, z))
}

proptest! {
    #[test]
    fn random_point_stamped_round_trips(h in arb_header(), p in arb_point(), big in any::<bool>()) {
        let msg = PointStamped { header: h, point: p };
        let e = if big { Endianness::Big } else { Endianness::Little };
        prop_assert_eq!(decode::<PointStamped>(&encode(&msg, e).unwrap()).unwrap(), msg);
    }

    #[test]
    fn random_joy_and_clouds_round_trip(
        h in arb_header(),
        axes in proptest::collection::vec(-1f32..1.0, 0..10),
        buttons in proptest::collection::vec(any::<i32>(), 0..12),
        data in proptest::collection::vec(any::<u8>(), 0..200),
        names in proptest::collection::vec("[a-z]{1,9}", 0..5),
        big in any::<bool>(),
    ) {
        let e = if big { Endianness::Big } else { Endianness::Little };
        let joy = Joy { header: h.clone(), axes, buttons };
        prop_assert_eq!(decode::<Joy>(&encode(&joy, e).unwrap()).unwrap(), joy);
        let cloud = PointCloud2 {
            header: h,
            height: 1,
            width: data.len() as u32,
            fields: names.into_iter().enumerate().map(|(i, name)| PointField { name, offset: i as u32, datatype: 2, count: 1 }).collect(),
            is_bigendian: big,
            point_step: 1,
            row_step: data.len() as u32,
            data,
            is_dense: false,
        };
        prop_assert_eq!(decode::<PointCloud2>(&encode(&cloud, e).unwrap()).unwrap(), cloud);
    }

    #[test]
    fn random_odometry_round_trips(h in arb_header(), p in arb_point(), yaw in -3.2f64..3.2, c in -10f64..10.0) {
        let msg = Odometry {
            header: h,
            child_frame_id: "sensor".into(),
            pose: PoseWithCovariance { pose: Pose { position: p, orientation: Quaternion::from_yaw(yaw) }, covariance: cov(c) },
            twist: TwistWithCovariance::default(),
        };
        prop_assert_eq!(decode::<Odometry>(&encode(&msg, Endianness::Little).unwrap()).unwrap(), msg);
    }

    #[test]
    fn decoding_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = decode::<PointCloud2>(&bytes);
        let _ = decode::<MarkerArray>(&bytes);
        let _ = decode::<Odometry>(&bytes);
    }
}

#[test]
fn message_type_names() {
    assert_eq!(Odometry::ros_type(), "nav_msgs/msg/Odometry");
    assert_eq!(PointCloud2::ros_type(), "sensor_msgs/msg/PointCloud2");
    assert_eq!(RosString::ros_type(), "std_msgs/msg/String");
    assert_eq!(
        UvCoordinate::ros_type(),
        "visualization_msgs/msg/UVCoordinate"
    );
    assert_eq!(Quaternion::default(), Quaternion::IDENTITY);
    let q = Quaternion::from_yaw(0.7).to_unit().unwrap();
    assert!((q.euler_angles().2 - 0.7).abs() < 1e-12);
    assert!(
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 0.0
        }
        .to_unit()
        .is_none()
    );
}
