//! `fields.mcap`: snapshots and histories written by `McapWriter` read back exactly, with
//! the `mcap` crate's own reader; Foxglove's conventions (JSON channels with JSON Schemas,
//! `foxglove.Grid` per component) are checked on the raw file.
#![allow(clippy::unwrap_used, missing_docs)]

use std::collections::BTreeSet;

use fracture_api::results::{CrackTipRow, EnergyRow, FieldComponent, Snapshot};
use fracture_results::mcapfile::{
    GridMessage, McapContents, McapWriter, log_time, read_crack_tips, read_energy, read_snapshots,
};

fn snapshot(index: u32, time: f64) -> Snapshot {
    let (nx, ny) = (7u32, 5u32);
    let n = (nx * ny) as usize;
    // Values with awkward bits: tiny, huge, negative, NaN (no material) and -0.
    let sxx: Vec<f32> = (0..n)
        .map(|i| match i % 6 {
            0 => f32::NAN,
            1 => -0.0,
            2 => 1.0e-30 * i as f32,
            3 => -3.3e9 / (i as f32 + 0.7),
            4 => std::f32::consts::PI * i as f32,
            _ => f32::from_bits(0x3eaa_aaab + i as u32),
        })
        .collect();
    let vx: Vec<f32> = (0..n).map(|i| 0.1 * i as f32 - 1.7).collect();
    Snapshot {
        index,
        time,
        nx,
        ny,
        origin: [-0.001, 0.002],
        cell_size: 5.0e-4,
        fields: vec!["stress".into(), "velocity".into()],
        components: vec![
            FieldComponent {
                name: "sxx".into(),
                values: sxx,
            },
            FieldComponent {
                name: "vx".into(),
                values: vx,
            },
        ],
        cracks: vec![vec![[0.01, 0.02], [0.015, 0.02 + 1e-4 * index as f64]]],
        particles: None,
        slice: None,
    }
}

fn energy(i: usize) -> EnergyRow {
    EnergyRow {
        time: 1.0e-7 * i as f64,
        kinetic: 0.1 + i as f64 / 3.0,
        strain: 1.0 / (i as f64 + 7.0),
        external_work: 2.5e-3 * i as f64,
        dissipated: 0.0,
        total_error: -1.0e-17 * i as f64,
        fracture: 1.0e-3 * i as f64,
    }
}

fn tip(i: usize, t: u32) -> CrackTipRow {
    CrackTipRow {
        time: 1.0e-7 * i as f64,
        crack: 0,
        tip: t,
        x: 0.05 + 1e-5 * i as f64 / 3.0,
        y: 0.05,
        length: 0.02 + 1.0 / 3.0 * 1e-5 * i as f64,
        speed: 1234.5678 * i as f64,
        j1: 10.0 / 3.0,
        j2: -1.0e-3,
        k1: 1.1e6,
        k2: -2.0e4,
        growing: i % 2 == 1,
        j1_half: 10.1 / 3.0,
        j2_half: -1.5e-3,
        j1_double: 9.9 / 3.0,
        j2_double: -2.0e-3,
        k1_cod: 1.2e6,
        k2_cod: -3.0e4,
        zone_x: 0.021,
        zone_y: 0.0275,
        connected_x: 0.019,
        connected_y: 0.0275,
        zone_connected_x: 0.0205,
        zone_connected_y: 0.0275,
    }
}

/// Bitwise comparison of snapshots (NaN == NaN, -0 != 0).
fn assert_same_snapshot(a: &Snapshot, b: &Snapshot) {
    assert_eq!(a.index, b.index);
    assert_eq!(a.time.to_bits(), b.time.to_bits());
    assert_eq!(
        (a.nx, a.ny, a.origin, a.cell_size),
        (b.nx, b.ny, b.origin, b.cell_size)
    );
    assert_eq!(a.fields, b.fields);
    assert_eq!(a.cracks, b.cracks);
    assert_eq!(a.components.len(), b.components.len());
    for (ca, cb) in a.components.iter().zip(&b.components) {
        assert_eq!(ca.name, cb.name);
        let ba: Vec<u32> = ca.values.iter().map(|v| v.to_bits()).collect();
        let bb: Vec<u32> = cb.values.iter().map(|v| v.to_bits()).collect();
        // NaN has many encodings; the file keeps "no value", which reads back as f32::NAN.
        for (i, (x, y)) in ba.iter().zip(&bb).enumerate() {
            let (fx, fy) = (f32::from_bits(*x), f32::from_bits(*y));
            if fx.is_nan() {
                assert!(fy.is_nan(), "{}[{i}]: NaN became {fy}", ca.name);
            } else {
                assert_eq!(x, y, "{}[{i}]: {fx} became {fy}", ca.name);
            }
        }
    }
}

#[test]
fn snapshots_and_histories_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fields.mcap");
    let snaps: Vec<Snapshot> = (0..3).map(|k| snapshot(k, 5.0e-6 * k as f64)).collect();
    let rows: Vec<EnergyRow> = (0..25).map(energy).collect();
    let tips: Vec<CrackTipRow> = (0..25).flat_map(|i| [tip(i, 0), tip(i, 1)]).collect();

    let mut w = McapWriter::create(&path).unwrap();
    w.write_energy(&rows[..10]).unwrap();
    w.write_crack_tips(&tips[..20]).unwrap();
    w.write_snapshot(&snaps[0]).unwrap();
    w.write_energy(&rows[10..]).unwrap();
    w.write_crack_tips(&tips[20..]).unwrap();
    w.write_snapshot(&snaps[1]).unwrap();
    w.write_snapshot(&snaps[2]).unwrap();
    w.finish().unwrap();

    let back = read_snapshots(&path).unwrap();
    assert_eq!(back.len(), snaps.len());
    for (a, b) in snaps.iter().zip(&back) {
        assert_same_snapshot(a, b);
    }
    assert_eq!(read_energy(&path).unwrap(), rows);
    assert_eq!(read_crack_tips(&path).unwrap(), tips);
    let all = McapContents::read(&path).unwrap();
    assert!(!all.truncated);
    // One grid per component per snapshot, decoding to the same f32 bits.
    assert_eq!(all.grids.len(), 2 * snaps.len());
    for (name, t, g) in &all.grids {
        let s = snaps
            .iter()
            .find(|s| log_time(s.time) == log_time(*t))
            .unwrap();
        let c = s.component(name).unwrap();
        let v = g.values().unwrap();
        assert_eq!(v.len(), c.values.len());
        for (x, y) in v.iter().zip(&c.values) {
            assert!(x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()));
        }
        assert_eq!(g.column_count, s.nx);
        assert_eq!(g.row_stride, 4 * s.nx);
    }
}

#[test]
fn foxglove_conventions_hold_in_the_raw_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fields.mcap");
    let mut w = McapWriter::create(&path).unwrap();
    w.write_energy(&[energy(0), energy(1)]).unwrap();
    w.write_crack_tips(&[tip(0, 1)]).unwrap();
    let s = snapshot(0, 2.5e-6);
    w.write_snapshot(&s).unwrap();
    w.finish().unwrap();

    let bytes = std::fs::read(&path).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let topics: BTreeSet<String> = summary.channels.values().map(|c| c.topic.clone()).collect();
    let expected: BTreeSet<String> = [
        "/energy",
        "/crack_tips",
        "/snapshot",
        "/fields/sxx",
        "/fields/vx",
    ]
    .into_iter()
    .map(String::from)
    .collect();
    assert_eq!(topics, expected);
    for c in summary.channels.values() {
        assert_eq!(c.message_encoding, "json", "{}", c.topic);
        let schema = c.schema.as_ref().unwrap();
        assert_eq!(schema.encoding, "jsonschema", "{}", c.topic);
        let js: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        assert!(js.get("properties").is_some(), "{}: {js}", c.topic);
        if c.topic.starts_with("/fields/") {
            assert_eq!(schema.name, "foxglove.Grid");
            for key in [
                "timestamp",
                "frame_id",
                "pose",
                "column_count",
                "cell_size",
                "row_stride",
                "cell_stride",
                "fields",
                "data",
            ] {
                assert!(
                    js["properties"].get(key).is_some(),
                    "Grid schema lacks {key}"
                );
            }
        }
    }
    // Every message: JSON, log time = sim time in ns; grids carry Foxglove's fields.
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        assert_eq!(m.log_time, m.publish_time);
        if m.channel.topic.starts_with("/fields/") {
            assert_eq!(m.log_time, 2_500);
            let g: GridMessage = serde_json::from_value(v.clone()).unwrap();
            assert_eq!(g.timestamp.sec, 0);
            assert_eq!(g.timestamp.nsec, 2_500);
            assert_eq!(g.fields.len(), 1);
            assert_eq!(v["fields"][0]["type"], 7, "FLOAT32");
            assert_eq!(
                v["fields"][0]["name"],
                m.channel.topic.trim_start_matches("/fields/")
            );
            assert_eq!(g.cell_stride, 4);
            // Cells are centred on the nodes.
            assert!((g.pose.position.x - (s.origin[0] - 0.5 * s.cell_size)).abs() < 1e-15);
            assert_eq!(g.pose.orientation.w, 1.0);
        }
        if m.channel.topic == "/energy" {
            let t = v["time"].as_f64().unwrap();
            assert_eq!(m.log_time, log_time(t));
        }
    }
}

#[test]
fn flushed_snapshots_survive_an_unfinished_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fields.mcap");
    let mut w = McapWriter::create(&path).unwrap();
    w.write_energy(&[energy(0)]).unwrap();
    w.write_snapshot(&snapshot(0, 0.0)).unwrap();
    w.write_energy(&[energy(1)]).unwrap();
    w.write_snapshot(&snapshot(1, 1.0e-6)).unwrap();
    // What a reader sees while the run goes on (or after a crash): the writer has not
    // finished, so there is no summary section or closing magic.
    let partial = std::fs::read(&path).unwrap();
    let got = McapContents::from_bytes(&partial).unwrap();
    assert!(got.truncated);
    assert_eq!(got.snapshots.len(), 2);
    assert_same_snapshot(&got.snapshots[1], &snapshot(1, 1.0e-6));
    assert_eq!(got.energy, vec![energy(0), energy(1)]);
    // Cut anywhere (a crash mid-write): always readable, and what is read is a prefix of
    // what was written.
    let mut last = 0;
    for cut in (8..=partial.len()).step_by(37).chain([partial.len() - 1]) {
        let got = McapContents::from_bytes(&partial[..cut]).unwrap();
        assert!(got.truncated);
        assert!(
            got.snapshots.len() >= last || cut == partial.len() - 1,
            "cut {cut}"
        );
        last = got.snapshots.len();
        for (k, s) in got.snapshots.iter().enumerate() {
            assert_same_snapshot(s, &snapshot(k as u32, 1.0e-6 * k as f64));
        }
        assert!(got.energy.len() <= 2);
    }
    assert_eq!(last, 2);
    w.finish().unwrap();
    assert_eq!(read_snapshots(&path).unwrap().len(), 2);
}

#[test]
fn scene_metadata_is_recorded() {
    let scene = fracture_api::validate::parse_scene(
        r#"{"name": "meta", "grid": {"cell_size": 0.001, "min": [0,0], "max": [0.01,0.01]},
            "materials": {"m": {"model": "linear_elastic", "density": 1000.0,
                                 "youngs_modulus": 1e9, "poissons_ratio": 0.3}},
            "bodies": [{"material": "m", "region": {"rectangle": {"min": [0.002,0.002], "max": [0.008,0.008]}}}],
            "time": {"end": 1e-6}}"#,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fields.mcap");
    let mut w = McapWriter::create(&path).unwrap();
    w.write_scene(&scene).unwrap();
    w.flush().unwrap();
    let partial = McapContents::from_bytes(&std::fs::read(&path).unwrap()).unwrap();
    assert_eq!(partial.scene.unwrap()["hash"], scene.hash());
    w.finish().unwrap();
    let meta = McapContents::read(&path).unwrap().scene.unwrap();
    assert_eq!(meta["name"], "meta");
    assert_eq!(meta["hash"], scene.hash());
    assert_eq!(meta["json"], scene.canonical_json());
}

#[test]
fn writers_can_move_to_another_thread() {
    // The server writes each job's file from its own task.
    fn assert_send<T: Send>() {}
    assert_send::<McapWriter>();
    assert_send::<fracture_worker::LocalOutput>();
    assert_send::<McapContents>();
}
