use super::*;
use fracture_api::results::FieldComponent;
use std::f64::consts::PI;

fn snapshot(nx: u32, ny: u32, h: f64, comps: Vec<(&str, Vec<f32>)>) -> Snapshot {
    Snapshot {
        index: 3,
        time: 12.5e-6,
        nx,
        ny,
        origin: [0.0, 0.0],
        cell_size: h,
        fields: vec!["stress".into(), "fringe".into()],
        components: comps
            .into_iter()
            .map(|(n, values)| FieldComponent {
                name: n.into(),
                values,
            })
            .collect(),
        cracks: vec![],
        particles: None,
        slice: None,
    }
}

/// Decode a PNG into (width, height, RGB bytes).
fn decode(png_bytes: &[u8]) -> (u32, u32, Vec<u8>) {
    let dec = png::Decoder::new(std::io::Cursor::new(png_bytes));
    let mut reader = dec.read_info().expect("png header");
    let mut buf = vec![0u8; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("png frame");
    buf.truncate(info.buffer_size());
    assert_eq!(info.color_type, png::ColorType::Rgb);
    (info.width, info.height, buf)
}

trait WithLegend {
    fn with_legend(self) -> Self;
}

impl WithLegend for RenderOptions {
    fn with_legend(self) -> Self {
        RenderOptions {
            legend: true,
            ..self
        }
    }
}

fn no_legend(ppc: f64) -> RenderOptions {
    RenderOptions {
        px_per_cell: Some(ppc),
        legend: false,
        ..RenderOptions::default()
    }
}

#[test]
fn renders_signed_and_fringe_fields() {
    let nx = 21;
    let ny = 11;
    let vals: Vec<f32> = (0..nx * ny)
        .map(|i| if i == 5 { f32::NAN } else { i as f32 - 100.0 })
        .collect();
    let mut snap = snapshot(
        nx,
        ny,
        0.001,
        vec![
            ("sxx", vals.clone()),
            ("fringe", vals.iter().map(|v| v.abs() / 50.0).collect()),
        ],
    );
    snap.cracks = vec![vec![[0.0, 0.005], [0.01, 0.005]]];
    for f in ["sxx", "stress", "fringe"] {
        let png = render_png(&snap, f).expect("renders");
        assert_eq!(&png[1..4], b"PNG");
    }
    assert!(matches!(
        render_png(&snap, "vx"),
        Err(RenderError::UnknownField(_))
    ));
}

#[test]
fn image_dimensions_follow_px_per_cell() {
    // 21 × 11 nodes = 20 × 10 cells.
    let snap = snapshot(21, 11, 1e-3, vec![("sxx", vec![1.0e6; 21 * 11])]);
    for (ppc, w, h) in [
        (4.0, 80, 40),
        (7.5, 150, 75),
        (1.0, 20, 10),
        (16.0, 320, 160),
    ] {
        let r = render_png_with(&snap, "sxx", &no_legend(ppc)).expect("renders");
        let (pw, ph, _) = decode(&r.png);
        assert_eq!((pw, ph), (w, h), "{ppc} px/cell");
        assert_eq!((r.report.width, r.report.height), (w, h));
        assert_eq!(r.report.px_per_cell, ppc);
        // With the legend the field area keeps that size, the PNG grows around it.
        let opts = RenderOptions {
            px_per_cell: Some(ppc),
            ..RenderOptions::default()
        };
        let r = render_png_with(&snap, "sxx", &opts).expect("renders");
        assert_eq!(r.report.plot[2..], [w, h]);
        let (pw, ph, _) = decode(&r.png);
        assert_eq!((pw, ph), (r.report.width, r.report.height));
        assert!(pw > w && ph > h);
    }
    // A width instead: 100 px over 20 cells = 5 px/cell.
    let opts = RenderOptions {
        width: Some(100),
        legend: false,
        ..RenderOptions::default()
    };
    let r = render_png_with(&snap, "sxx", &opts).expect("renders");
    assert_eq!((r.report.width, r.report.height), (100, 50));
    // The default is at least 4 px per cell (here more: a small grid).
    let r = render_png_with(&snap, "sxx", &RenderOptions::default()).expect("renders");
    assert!(r.report.px_per_cell >= MIN_DEFAULT_PX_PER_CELL);
    let big = snapshot(501, 251, 5e-4, vec![("sxx", vec![0.0; 501 * 251])]);
    let r = render_png_with(&big, "sxx", &RenderOptions::default()).expect("renders");
    assert_eq!(r.report.px_per_cell, 4.0);
    assert_eq!(r.report.plot[2..], [2000, 1000]);
    // Nonsense and oversized requests are errors, not huge allocations.
    for p in [0.0, -1.0, f64::NAN] {
        assert!(matches!(
            render_png_with(&snap, "sxx", &no_legend(p)),
            Err(RenderError::BadOptions(_))
        ));
    }
    assert!(matches!(
        render_png_with(&big, "sxx", &no_legend(64.0)),
        Err(RenderError::BadOptions(_))
    ));
}

#[test]
fn empty_nodes_are_background_and_linear_fields_are_reproduced() {
    // v = 2·ix + 3·iy on the left 11 columns of nodes, NaN on the right.
    let (nx, ny) = (21usize, 11usize);
    let vals: Vec<f32> = (0..nx * ny)
        .map(|n| {
            let (ix, iy) = (n % nx, n / nx);
            if ix <= 10 {
                (2 * ix + 3 * iy) as f32
            } else {
                f32::NAN
            }
        })
        .collect();
    let snap = snapshot(nx as u32, ny as u32, 1.0, vec![("sxx", vals)]);
    let (_, r) = rasterize(&snap, "sxx", &no_legend(8.0)).expect("rasterizes");
    let mut checked = [0usize; 3];
    for j in 0..r.height {
        for i in 0..r.width {
            let [x, y] = r.position(i, j);
            let v = r.get(i, j);
            if x <= 10.0 {
                assert!((v - (2.0 * x + 3.0 * y)).abs() < 1e-9, "({x}, {y}): {v}");
                checked[0] += 1;
            } else if x < 11.0 {
                // The cell between the last valid column and the first empty one: material
                // up to its middle (the valid weight reaches ½ there), and the values of the
                // valid side.
                assert_eq!(v.is_finite(), x <= 10.5, "({x}, {y})");
                if v.is_finite() {
                    assert!((v - (20.0 + 3.0 * y)).abs() < 1e-9);
                }
                checked[1] += 1;
            } else {
                assert!(v.is_nan(), "no valid node next to ({x}, {y}), yet {v}");
                checked[2] += 1;
            }
        }
    }
    assert!(checked.iter().all(|&n| n > 0), "{checked:?}");
}

#[test]
fn legend_names_the_quantity_and_unit() {
    let n = 21 * 11;
    let cases = [
        ("sxx", 5.0e7f32, "σxx (MPa)"),
        ("sxy", -2.0e5, "σxy (kPa)"),
        ("speed", 12.0, "|v| (m/s)"),
        ("vx", 0.02, "vx (mm/s)"),
        ("ux", 3.0e-5, "ux (µm)"),
        ("exx", 2.0e-3, "εxx (×1e-3)"),
        ("fringe", 3.0, "fringe order N"),
    ];
    for (name, v, label) in cases {
        let vals: Vec<f32> = (0..n).map(|i| v * (i as f32 / n as f32)).collect();
        let snap = snapshot(21, 11, 1e-3, vec![(name, vals)]);
        let r = render_png_with(&snap, name, &RenderOptions::default()).expect("renders");
        assert_eq!(r.report.label, label);
    }
}

/// A 3D run's slice: its components get their quantity and unit, and the title names the
/// plane (the picture's axes being the other two).
#[test]
fn slices_name_their_plane_and_3d_components() {
    let n = 21 * 11;
    for (name, v, label) in [
        ("syz", 5.0e7f32, "σyz (MPa)"),
        ("vz", 0.02, "vz (mm/s)"),
        ("uz", 3.0e-5, "uz (µm)"),
        ("ezz", 2.0e-3, "εzz (×1e-3)"),
    ] {
        let vals: Vec<f32> = (0..n).map(|i| v * (i as f32 / n as f32)).collect();
        let mut snap = snapshot(21, 11, 1e-3, vec![(name, vals)]);
        snap.slice = Some(fracture_api::results::SnapshotSlice {
            normal: "y".into(),
            at: 0.002,
            node_at: 0.002,
            axes: ["x".into(), "z".into()],
        });
        let r = render_png_with(&snap, name, &RenderOptions::default()).expect("renders");
        assert_eq!(r.report.label, label);
        assert!(
            legend::title(&snap, "q").ends_with("#3   y = 2 mm"),
            "{}",
            legend::title(&snap, "q")
        );
    }
    let flat = snapshot(21, 11, 1e-3, vec![("sxx", vec![0.0; n])]);
    assert!(legend::title(&flat, "q").ends_with("#3"));
}

/// Whether any pixel of the PNG has the warning colour.
fn has_warning_ink(png_bytes: &[u8]) -> bool {
    let (_, _, px) = decode(png_bytes);
    px.chunks_exact(3).any(|p| p == WARN)
}

#[test]
fn aliasing_warning_for_fast_fringes_only() {
    // N = a·ix: a fringes per cell, a/4 per pixel at 4 px/cell.
    let (nx, ny) = (21usize, 11usize);
    let field = |a: f32| -> Vec<f32> { (0..nx * ny).map(|n| a * (n % nx) as f32).collect() };
    let opts = RenderOptions {
        px_per_cell: Some(4.0),
        ..RenderOptions::default()
    };
    let smooth = snapshot(21, 11, 1e-3, vec![("fringe", field(0.5))]);
    let r = render_png_with(&smooth, "fringe", &opts).expect("renders");
    assert!(!r.report.aliased);
    assert_eq!(r.report.aliased_pairs, 0);
    let m = r.report.max_fringes_per_pixel.expect("fringe picture");
    assert!((m - 0.125).abs() < 1e-6, "{m}");
    assert!(!has_warning_ink(&r.png));

    let fast = snapshot(21, 11, 1e-3, vec![("fringe", field(8.0))]);
    let r = render_png_with(&fast, "fringe", &opts).expect("renders");
    assert!(r.report.aliased);
    assert!(r.report.aliased_pairs > 0);
    let m = r.report.max_fringes_per_pixel.expect("fringe picture");
    assert!((m - 2.0).abs() < 1e-6, "{m}");
    assert!(has_warning_ink(&r.png), "the legend carries the warning");
    // More pixels per cell resolve it: 8 fringes per cell at 16 px/cell.
    let r = render_png_with(&fast, "fringe", &no_legend(16.0)).expect("renders");
    assert!(!r.report.aliased);
    // Non-fringe fields carry no fringe diagnosis.
    let s = snapshot(21, 11, 1e-3, vec![("sxx", field(8.0e6))]);
    let r = render_png_with(&s, "sxx", &opts).expect("renders");
    assert_eq!(r.report.max_fringes_per_pixel, None);
    assert!(!r.report.aliased);
}

/// Williams' near-tip field of a stationary mode I crack (tip at the origin, crack faces
/// along θ = ±π; e.g. Anderson, Fracture Mechanics, table 2.1):
///   σxx = K/√(2πr)·cos(θ/2)·[1 − sin(θ/2)·sin(3θ/2)]
///   σyy = K/√(2πr)·cos(θ/2)·[1 + sin(θ/2)·sin(3θ/2)]
///   σxy = K/√(2πr)·cos(θ/2)·sin(θ/2)·cos(3θ/2)
/// so σ1 − σ2 = 2·sqrt(((σxx − σyy)/2)² + σxy²) = K·|sin θ|/√(2πr), and the isochromatic
/// fringe order is N = (h/f_σ)·K·|sin θ|/√(2πr).
fn williams(k: f64, x: f64, y: f64) -> [f64; 3] {
    let r = x.hypot(y);
    let t = y.atan2(x);
    let a = k / (2.0 * PI * r).sqrt();
    let (c, s, s3, c3) = (
        (t / 2.0).cos(),
        (t / 2.0).sin(),
        (1.5 * t).sin(),
        (1.5 * t).cos(),
    );
    [
        a * c * (1.0 - s * s3),
        a * c * (1.0 + s * s3),
        a * c * s * c3,
    ]
}

fn fringe_order(per_pa: f64, s: [f64; 3]) -> f64 {
    per_pa * 2.0 * (0.5 * (s[0] - s[1])).hypot(s[2])
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

/// The isochromatics of a stationary mode I crack against the analytic fringe pattern.
/// Grid: 81 × 61 nodes, 1 mm cells, tip at node (40, 30), crack along the row to the left
/// edge; Homalite h/f_σ = 9.5 mm / 23 kN/m; K_I = 2.66 MPa·√m, so N ≈ 8 at r = 3 cells ahead
/// of θ = 90° and ≈ 2 at the corners: near the tip N changes by more than one fringe per
/// cell, which node-sampled sin²(πN) turns into noise. Rendered at 8 px/cell.
/// Tolerances (away from the tip, r > 3 cells): |N_pixel − N_exact| < 0.2 fringe, < 0.02
/// beyond 10 cells, rms < 0.01 (bilinear error ~ h²/8·|∇²N|, N'' ~ N/r²; measured 0.124,
/// 0.007, 0.004); from interpolated stresses < 0.4, < 0.03, rms < 0.02 (measured 0.336,
/// 0.019, 0.011); pixel intensity correlation
/// with sin²(πN_exact) > 0.95; along θ = 90° the dark fringes are where N is an integer
/// (same count, each within 0.25 cell of r_k = (cK/(k√(2π)))²).
#[test]
fn mode_i_isochromatics_match_williams() {
    let (nx, ny, h) = (81usize, 61usize, 1e-3);
    let tip = [40.0 * h, 30.0 * h];
    let per_pa = 9.5e-3 / 23.0e3;
    let k = 2.66e6;
    // The identity σ1 − σ2 = K|sin θ|/√(2πr) holds for the formulas above.
    for (x, y) in [(0.01, 0.003), (-0.02, 0.001), (0.004, -0.03)] {
        let n = fringe_order(per_pa, williams(k, x, y));
        let exact = per_pa * k * y.atan2(x).sin().abs() / (2.0 * PI * x.hypot(y)).sqrt();
        assert!((n - exact).abs() < 1e-9 * exact.max(1.0));
    }
    let mut comps: Vec<Vec<f32>> = vec![Vec::new(); 4];
    for iy in 0..ny {
        for ix in 0..nx {
            let (x, y) = (ix as f64 * h - tip[0], iy as f64 * h - tip[1]);
            let s = if x == 0.0 && y == 0.0 {
                [f64::NAN; 3] // the singular tip node: empty
            } else {
                williams(k, x, y)
            };
            comps[0].push(s[0] as f32);
            comps[1].push(s[1] as f32);
            comps[2].push(s[2] as f32);
            comps[3].push(fringe_order(per_pa, s) as f32);
        }
    }
    let mut it = comps.into_iter();
    let mut next = || it.next().unwrap_or_default();
    let (a, b, c, d) = (next(), next(), next(), next());
    let mut snap = snapshot(
        nx as u32,
        ny as u32,
        h,
        vec![("sxx", a), ("syy", b), ("sxy", c), ("fringe", d)],
    );
    snap.cracks = vec![vec![[0.0, tip[1]], tip]];
    let exact_n = |p: [f64; 2]| {
        let (x, y) = (p[0] - tip[0], p[1] - tip[1]);
        per_pa * k * y.atan2(x).sin().abs() / (2.0 * PI * x.hypot(y)).sqrt()
    };
    let ppc = 8.0;

    // Both ways of getting N per pixel: the nodal fringe order, and the nodal stresses.
    for per_pa_opt in [None, Some(per_pa)] {
        let opts = RenderOptions {
            fringe_per_pa: per_pa_opt,
            cracks: false,
            legend: false,
            ..no_legend(ppc)
        };
        let (_, r) = rasterize(&snap, "fringe", &opts).expect("rasterizes");
        let (mut max_near, mut max_far, mut sq, mut n) = (0.0f64, 0.0f64, 0.0, 0usize);
        for j in 0..r.height {
            for i in 0..r.width {
                let p = r.position(i, j);
                let rr = (p[0] - tip[0]).hypot(p[1] - tip[1]) / h;
                if rr <= 3.0 {
                    continue;
                }
                let e = (r.get(i, j) - exact_n(p)).abs();
                assert!(e.is_finite(), "pixel ({i}, {j}) lost its value");
                max_near = max_near.max(e);
                if rr > 10.0 {
                    max_far = max_far.max(e);
                }
                sq += e * e;
                n += 1;
            }
        }
        let rms = (sq / n as f64).sqrt();
        eprintln!(
            "fringe order from {}: max |ΔN| = {max_near:.4} (r > 3 cells), {max_far:.4} \
             (r > 10 cells), rms {rms:.4} over {n} pixels",
            if per_pa_opt.is_some() {
                "stresses"
            } else {
                "nodal N"
            }
        );
        // Interpolating the stresses is the less accurate way near a singular tip: each
        // component has the full K/√r curvature, N only its |sin θ| share of it.
        let (near, far, rms_tol) = if per_pa_opt.is_some() {
            (0.4, 0.03, 0.02)
        } else {
            (0.2, 0.02, 0.01)
        };
        assert!(max_near < near, "{max_near}");
        assert!(max_far < far, "{max_far}");
        assert!(rms < rms_tol, "{rms}");
    }

    // FRACTURE_RENDER_SAMPLES=DIR keeps the pictures for a look.
    if let Some(dir) = std::env::var_os("FRACTURE_RENDER_SAMPLES") {
        let dir = std::path::PathBuf::from(dir);
        for (f, name) in [
            ("fringe", "williams-fringe.png"),
            ("sxx", "williams-sxx.png"),
        ] {
            let r = render_png_with(&snap, f, &no_legend(ppc).with_legend()).expect("renders");
            std::fs::write(dir.join(name), r.png).expect("writes sample");
        }
        let old = render_png_with(&snap, "fringe", &no_legend(1.0)).expect("renders");
        std::fs::write(dir.join("williams-fringe-1px.png"), old.png).expect("writes sample");
    }

    // The picture itself: intensities against sin²(πN_exact).
    let rendered = render_png_with(&snap, "fringe", &no_legend(ppc)).expect("renders");
    // Next to the tip the nodal N jumps by ~13 fringes per cell: the report says so, and
    // only there (within 2 cells of the tip).
    let rep = &rendered.report;
    let b = rep
        .aliased_box
        .expect("the tip's neighbourhood is aliased at 8 px/cell");
    assert!(rep.aliased);
    for (x, y) in [(b[0], b[1]), (b[2], b[3])] {
        assert!(
            (x - tip[0]).abs() < 2.0 * h && (y - tip[1]).abs() < 2.0 * h,
            "{rep:?}"
        );
    }
    let (w, hh, px) = decode(&rendered.png);
    let (_, r) = rasterize(&snap, "fringe", &no_legend(ppc)).expect("rasterizes");
    assert_eq!((w as usize, hh as usize), (r.width, r.height));
    let crack_row = |p: [f64; 2]| (p[1] - tip[1]).abs() < 0.5 * h && p[0] < tip[0];
    let (mut got, mut want, mut naive) = (Vec::new(), Vec::new(), Vec::new());
    let mut near = (Vec::new(), Vec::new(), Vec::new()); // 3 < r < 8 cells
    for j in 0..r.height {
        for i in 0..r.width {
            let p = r.position(i, j);
            if (p[0] - tip[0]).hypot(p[1] - tip[1]) <= 3.0 * h || crack_row(p) {
                continue;
            }
            got.push(px[(j * r.width + i) * 3] as f64 / 255.0);
            want.push((PI * exact_n(p)).sin().powi(2));
            // What the old renderer showed: sin²(πN) of the nearest node.
            let (ix, iy) = ((p[0] / h).round(), (p[1] / h).round());
            let node = [ix * h, iy * h];
            naive.push(if node == tip {
                0.0
            } else {
                (PI * exact_n(node)).sin().powi(2)
            });
            if (p[0] - tip[0]).hypot(p[1] - tip[1]) < 8.0 * h {
                near.0.push(got[got.len() - 1]);
                near.1.push(want[want.len() - 1]);
                near.2.push(naive[naive.len() - 1]);
            }
        }
    }
    let corr = correlation(&got, &want);
    let corr_naive = correlation(&naive, &want);
    let corr_near = correlation(&near.0, &near.1);
    let corr_near_naive = correlation(&near.2, &near.1);
    eprintln!(
        "intensity correlation with sin²(πN_exact), r > 3 cells: {corr:.4} (node-sampled: \
         {corr_naive:.4}); 3 < r < 8 cells: {corr_near:.4} (node-sampled: \
         {corr_near_naive:.4}); max fringe change {:.3} per pixel",
        rendered.report.max_fringes_per_pixel.unwrap_or(f64::NAN)
    );
    assert!(corr > 0.95, "{corr}");
    assert!(corr_near > 0.9, "{corr_near}");
    assert!(corr > corr_naive && corr_near > corr_near_naive);

    // Dark fringes along θ = 90° (the pixel column through the tip, upwards from r = 3 cells).
    let col = (tip[0] / h * ppc).round() as usize; // the column whose centre is nearest x_tip
    let mut runs: Vec<(usize, usize)> = Vec::new(); // dark runs of pixel rows
    let mut start = None;
    let top_j = 0usize;
    let tip_j = ((ny - 1) as f64 * ppc - tip[1] / h * ppc) as usize;
    let first_j = tip_j - (3.0 * ppc) as usize - 1;
    for j in (top_j..=first_j).rev() {
        let dark = px[(j * r.width + col) * 3] < 13; // I < 0.05
        match (dark, start) {
            (true, None) => start = Some(j),
            (false, Some(s)) => {
                runs.push((j + 1, s));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        runs.push((top_j, s));
    }
    let n_low = exact_n(r.position(col, top_j));
    let n_high = exact_n(r.position(col, first_j));
    let integers: Vec<i64> = ((n_low.ceil() as i64)..=(n_high.floor() as i64)).collect();
    eprintln!(
        "θ = 90°: N from {n_low:.2} to {n_high:.2}; dark bands {} (integers {:?})",
        runs.len(),
        integers
    );
    assert_eq!(runs.len(), integers.len(), "{runs:?}");
    // Bands run outwards with N falling: band m is N = n_high.floor() − m.
    let c0 = per_pa * k / (2.0 * PI).sqrt();
    for (m, (a, b)) in runs.iter().enumerate() {
        let kk = n_high.floor() - m as f64;
        let r_k = (c0 / kk).powi(2); // N(r_k) = k on θ = 90°
        let y_mid = 0.5 * (r.position(col, *a)[1] + r.position(col, *b)[1]);
        let err = (y_mid - tip[1] - r_k).abs() / h;
        assert!(err < 0.25, "fringe N = {kk}: {err} cells off");
    }
}
