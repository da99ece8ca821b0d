//! PointCloud2 decoding of different layouts (packed xyz + label, padded
//! xyzi, big-endian, organised clouds with row padding), rejection of
//! malformed clouds, and property tests: random layouts written by an
//! independent reference encoder in this file decode to the values written.

use proptest::prelude::*;
use sornav_platform_scout::msg::{Header, PointCloud2, PointField};
use sornav_platform_scout::pointcloud::{
    CloudError, CloudView, Datatype, FieldSpec, encode_cloud, encode_xyzi, encode_xyzl,
    xyzi_fields, xyzl_fields,
};

fn field(name: &str, offset: u32, datatype: u8) -> PointField {
    PointField {
        name: name.into(),
        offset,
        datatype,
        count: 1,
    }
}

/// Reference writer: one scalar at `offset` of `buf` (independent of the
/// crate's encoder).
fn put(buf: &mut [u8], offset: usize, t: Datatype, big: bool, v: f64) {
    let bytes: Vec<u8> = match (t, big) {
        (Datatype::Int8, _) => vec![(v as i8) as u8],
        (Datatype::Uint8, _) => vec![v as u8],
        (Datatype::Int16, false) => (v as i16).to_le_bytes().to_vec(),
        (Datatype::Int16, true) => (v as i16).to_be_bytes().to_vec(),
        (Datatype::Uint16, false) => (v as u16).to_le_bytes().to_vec(),
        (Datatype::Uint16, true) => (v as u16).to_be_bytes().to_vec(),
        (Datatype::Int32, false) => (v as i32).to_le_bytes().to_vec(),
        (Datatype::Int32, true) => (v as i32).to_be_bytes().to_vec(),
        (Datatype::Uint32, false) => (v as u32).to_le_bytes().to_vec(),
        (Datatype::Uint32, true) => (v as u32).to_be_bytes().to_vec(),
        (Datatype::Float32, false) => (v as f32).to_le_bytes().to_vec(),
        (Datatype::Float32, true) => (v as f32).to_be_bytes().to_vec(),
        (Datatype::Float64, false) => v.to_le_bytes().to_vec(),
        (Datatype::Float64, true) => v.to_be_bytes().to_vec(),
    };
    buf[offset..offset + bytes.len()].copy_from_slice(&bytes);
}

#[test]
fn packed_xyz_label() {
    let rows = [[1.0, 2.0, 3.0, 14.0], [-1.5, 0.25, 0.0, 2.0]];
    let cloud = encode_xyzl(Header::default(), &rows).unwrap();
    assert_eq!(
        (cloud.point_step, cloud.row_step, cloud.data.len()),
        (16, 32, 32)
    );
    let v = CloudView::new(&cloud).unwrap();
    let l = v.labelled_points("label").unwrap();
    assert_eq!(l.points.len(), 2);
    assert_eq!(l.points[0].label.0, 14);
    assert_eq!(
        (l.points[1].position.x, l.points[1].position.y),
        (-1.5, 0.25)
    );
    assert_eq!((l.non_finite, l.bad_label), (0, 0));
    assert!(matches!(v.labelled_points("class"), Err(CloudError::MissingField(f)) if f == "class"));
}

#[test]
fn padded_xyzi_like_pcl() {
    assert_eq!(xyzi_fields().1, 32);
    let cloud = encode_xyzi(Header::default(), &[[1.0, 2.0, 3.0, 0.5]]).unwrap();
    assert_eq!((cloud.point_step, cloud.row_step), (32, 32));
    // Bytes 12..16 (padding) and 20..32 are zero.
    assert!(
        cloud.data[12..16]
            .iter()
            .chain(&cloud.data[20..32])
            .all(|b| *b == 0)
    );
    let v = CloudView::new(&cloud).unwrap();
    let s = v.points_with("intensity").unwrap();
    assert_eq!(s.points[0].1, 0.5);
    assert_eq!(v.xyz().unwrap().0[0], nalgebra::Point3::new(1.0, 2.0, 3.0));
}

#[test]
fn big_endian_with_reordered_fields_and_f64() {
    // label (u16) first, then z, y, x as float64: 2 + 6 padding + 24 = 32.
    let cloud = PointCloud2 {
        header: Header::default(),
        height: 1,
        width: 1,
        fields: vec![
            field("label", 0, 4),
            field("z", 8, 8),
            field("y", 16, 8),
            field("x", 24, 8),
        ],
        is_bigendian: true,
        point_step: 32,
        row_step: 32,
        data: {
            let mut d = vec![0u8; 32];
            d[0..2].copy_from_slice(&300u16.to_be_bytes());
            d[8..16].copy_from_slice(&3.5f64.to_be_bytes());
            d[16..24].copy_from_slice(&(-2.0f64).to_be_bytes());
            d[24..32].copy_from_slice(&1.25f64.to_be_bytes());
            d
        },
        is_dense: true,
    };
    let l = CloudView::new(&cloud)
        .unwrap()
        .labelled_points("label")
        .unwrap();
    assert_eq!(l.points[0].label.0, 300);
    assert_eq!(
        (
            l.points[0].position.x,
            l.points[0].position.y,
            l.points[0].position.z
        ),
        (1.25, -2.0, 3.5)
    );
}

#[test]
fn organised_cloud_with_row_padding() {
    // 2 x 2 points of 12 bytes, rows padded to 32 bytes.
    let mut data = vec![0u8; 64];
    for row in 0..2 {
        for col in 0..2 {
            let base = row * 32 + col * 12;
            for (k, v) in [row as f64, col as f64, 9.0].iter().enumerate() {
                put(&mut data, base + 4 * k, Datatype::Float32, false, *v);
            }
        }
    }
    let cloud = PointCloud2 {
        header: Header::default(),
        height: 2,
        width: 2,
        fields: vec![field("x", 0, 7), field("y", 4, 7), field("z", 8, 7)],
        is_bigendian: false,
        point_step: 12,
        row_step: 32,
        data,
        is_dense: true,
    };
    let (pts, skipped) = CloudView::new(&cloud).unwrap().xyz().unwrap();
    assert_eq!(skipped, 0);
    let xy: Vec<(f64, f64)> = pts.iter().map(|p| (p.x, p.y)).collect();
    assert_eq!(xy, vec![(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)]);
}

#[test]
fn invalid_points_and_labels_are_counted_not_fused() {
    let rows = [
        [f64::NAN, 0.0, 0.0, 1.0],
        [0.0, f64::INFINITY, 0.0, 1.0],
        [1.0, 1.0, 1.0, 2.0],
    ];
    let cloud = encode_xyzl(Header::default(), &rows).unwrap();
    assert!(!cloud.is_dense);
    let l = CloudView::new(&cloud)
        .unwrap()
        .labelled_points("label")
        .unwrap();
    assert_eq!((l.points.len(), l.non_finite), (1, 2));
    // Float labels must be integers in u16 range.
    let fields = [
        FieldSpec::new("x", 0, Datatype::Float32),
        FieldSpec::new("y", 4, Datatype::Float32),
        FieldSpec::new("z", 8, Datatype::Float32),
        FieldSpec::new("label", 12, Datatype::Float32),
    ];
    let rows = [
        [0.0, 0.0, 0.0, 2.5],
        [0.0, 0.0, 0.0, -1.0],
        [0.0, 0.0, 0.0, 70000.0],
        [0.0, 0.0, 0.0, 7.0],
    ];
    let cloud = encode_cloud(
        Header::default(),
        &fields,
        16,
        false,
        rows.iter().map(|r| &r[..]),
    )
    .unwrap();
    let l = CloudView::new(&cloud)
        .unwrap()
        .labelled_points("label")
        .unwrap();
    assert_eq!((l.points.len(), l.bad_label), (1, 3));
    assert_eq!(l.points[0].label.0, 7);
}

fn base_cloud() -> PointCloud2 {
    let rows = [[1.0, 2.0, 3.0, 4.0], [5.0, 6.0, 7.0, 8.0]];
    encode_xyzl(Header::default(), &rows).unwrap()
}

#[test]
fn malformed_clouds_are_rejected_with_typed_errors() {
    let ok = base_cloud();
    assert!(CloudView::new(&ok).is_ok());

    let mut c = ok.clone();
    c.fields[3].datatype = 9;
    assert!(matches!(
        CloudView::new(&c),
        Err(CloudError::UnknownDatatype { code: 9, .. })
    ));

    let mut c = ok.clone();
    c.fields[3].offset = 14; // u32 at 14..18 > 16
    assert!(matches!(
        CloudView::new(&c),
        Err(CloudError::FieldOverrun { .. })
    ));

    let mut c = ok.clone();
    c.fields[0].count = 0;
    assert!(matches!(CloudView::new(&c), Err(CloudError::ZeroCount(_))));

    let mut c = ok.clone();
    c.fields[1].name = "x".into();
    assert!(matches!(
        CloudView::new(&c),
        Err(CloudError::DuplicateField(_))
    ));

    let mut c = ok.clone();
    c.data.pop();
    assert!(matches!(
        CloudView::new(&c),
        Err(CloudError::DataLength {
            expected: 32,
            actual: 31
        })
    ));

    let mut c = ok.clone();
    c.row_step = 16; // < width * point_step
    assert!(matches!(
        CloudView::new(&c),
        Err(CloudError::RowStepTooShort { .. })
    ));

    let mut c = ok.clone();
    c.point_step = 0;
    c.row_step = 0;
    c.data.clear();
    assert!(matches!(
        CloudView::new(&c),
        Err(CloudError::FieldOverrun { .. })
    ));
    c.fields.clear();
    assert!(matches!(
        CloudView::new(&c),
        Err(CloudError::ZeroPointStep(2))
    ));

    let mut c = ok.clone();
    c.width = u32::MAX;
    c.height = u32::MAX;
    assert!(CloudView::new(&c).is_err());

    let mut c = ok;
    c.fields.retain(|f| f.name != "z");
    assert!(
        matches!(CloudView::new(&c).unwrap().xyz(), Err(CloudError::MissingField(f)) if f == "z")
    );
}

#[test]
fn empty_cloud_is_valid() {
    let c = PointCloud2::default();
    let v = CloudView::new(&c).unwrap();
    assert!(v.is_empty());
    assert!(matches!(v.xyz(), Err(CloudError::MissingField(_))));
    let e = encode_cloud(
        Header::default(),
        &xyzl_fields(),
        16,
        false,
        std::iter::empty(),
    )
    .unwrap();
    assert_eq!(
        CloudView::new(&e)
            .unwrap()
            .labelled_points("label")
            .unwrap()
            .points
            .len(),
        0
    );
}

/// A random layout: x, y, z (f32 or f64) and a label of any integer type,
/// in random order with random gaps, random endianness, random row padding.
#[derive(Debug, Clone)]
struct Layout {
    order: Vec<usize>,
    gaps: Vec<u32>,
    coord: Datatype,
    label: Datatype,
    big: bool,
    width: u32,
    height: u32,
    row_pad: u32,
}

fn arb_layout() -> impl Strategy<Value = Layout> {
    (
        Just(vec![0usize, 1, 2, 3]).prop_shuffle(),
        proptest::collection::vec(0u32..5, 5),
        prop_oneof![Just(Datatype::Float32), Just(Datatype::Float64)],
        prop_oneof![
            Just(Datatype::Uint8),
            Just(Datatype::Uint16),
            Just(Datatype::Int32),
            Just(Datatype::Uint32),
            Just(Datatype::Float32),
            Just(Datatype::Float64)
        ],
        any::<bool>(),
        0u32..12,
        1u32..4,
        0u32..9,
    )
        .prop_map(
            |(order, gaps, coord, label, big, width, height, row_pad)| Layout {
                order,
                gaps,
                coord,
                label,
                big,
                width,
                height,
                row_pad,
            },
        )
}

proptest! {
    #[test]
    fn random_layouts_decode_to_the_written_values(
        layout in arb_layout(),
        values in proptest::collection::vec((-100i32..100, -100i32..100, -20i32..20, 0u16..250), 48),
    ) {
        let names = ["x", "y", "z", "label"];
        let mut fields = Vec::new();
        let mut offset = 0u32;
        for (slot, &k) in layout.order.iter().enumerate() {
            offset += layout.gaps[slot];
            let t = if k == 3 { layout.label } else { layout.coord };
            fields.push(field(names[k], offset, t.code()));
            offset += t.size() as u32;
        }
        let point_step = offset + layout.gaps[4];
        let row_step = point_step * layout.width + layout.row_pad;
        let n = (layout.width * layout.height) as usize;
        let mut data = vec![0xAAu8; (row_step * layout.height) as usize];
        // Coordinates on a 1/8 grid are exact in f32 and f64.
        let pts: Vec<[f64; 4]> = values[..n].iter().map(|(x, y, z, l)| [f64::from(*x) / 8.0, f64::from(*y) / 8.0, f64::from(*z) / 8.0, f64::from(*l)]).collect();
        for (i, p) in pts.iter().enumerate() {
            let (row, col) = (i as u32 / layout.width.max(1), i as u32 % layout.width.max(1));
            let base = (row * row_step + col * point_step) as usize;
            for f in &fields {
                let k = names.iter().position(|n| *n == f.name).unwrap();
                put(&mut data, base + f.offset as usize, Datatype::from_code(f.datatype).unwrap(), layout.big, p[k]);
            }
        }
        let cloud = PointCloud2 {
            header: Header::default(),
            height: layout.height,
            width: layout.width,
            fields,
            is_bigendian: layout.big,
            point_step,
            row_step,
            data,
            is_dense: true,
        };
        let view = CloudView::new(&cloud).unwrap();
        prop_assert_eq!(view.len(), n);
        let l = view.labelled_points("label").unwrap();
        prop_assert_eq!(l.points.len(), n);
        for (got, want) in l.points.iter().zip(&pts) {
            prop_assert_eq!(f64::from(got.position.x), want[0]);
            prop_assert_eq!(f64::from(got.position.y), want[1]);
            prop_assert_eq!(f64::from(got.position.z), want[2]);
            prop_assert_eq!(f64::from(got.label.0), want[3]);
        }
        // The crate's encoder and the reference agree on an unorganised copy.
        let specs: Vec<FieldSpec> = cloud.fields.iter().map(|f| FieldSpec::new(f.name.clone(), f.offset, Datatype::from_code(f.datatype).unwrap())).collect();
        let rows: Vec<[f64; 4]> = pts.iter().map(|p| {
            let mut r = [0.0; 4];
            for (j, f) in specs.iter().enumerate() {
                r[j] = p[names.iter().position(|n| *n == f.name).unwrap()];
            }
            r
        }).collect();
        let enc = encode_cloud(Header::default(), &specs, point_step, layout.big, rows.iter().map(|r| &r[..])).unwrap();
        let again = CloudView::new(&enc).unwrap().labelled_points("label").unwrap();
        prop_assert_eq!(again.points, l.points);
    }

    #[test]
    fn arbitrary_layouts_never_panic(
        fields in proptest::collection::vec(("[xyzl]", 0u32..40, 0u8..10, 0u32..3), 0..6),
        point_step in 0u32..40,
        row_step in 0u32..200,
        width in 0u32..8,
        height in 0u32..4,
        len in 0usize..300,
        big in any::<bool>(),
    ) {
        let cloud = PointCloud2 {
            header: Header::default(),
            height,
            width,
            fields: fields.into_iter().map(|(name, offset, datatype, count)| PointField { name, offset, datatype, count }).collect(),
            is_bigendian: big,
            point_step,
            row_step,
            data: vec![7u8; len],
            is_dense: false,
        };
        if let Ok(v) = CloudView::new(&cloud) {
            let _ = v.xyz();
            let _ = v.labelled_points("l");
            for f in v.fields() {
                for i in 0..v.len() {
                    prop_assert!(v.get(f, i, 0).is_some());
                }
            }
        }
    }
}
