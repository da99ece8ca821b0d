//! Procedural houses follow the embedded HM3D validation statistics
//! (`data/hm3d_val_stats.json`): house sizes, room types, objects per room
//! type; shuffled semantics breaks the room-object association and keeps the
//! objects.
//!
//! Houses imitate validation houses drawn by floor class with HM3D's
//! floor-count shares over all 900 scenes, so house sizes (rooms, area) are
//! compared with the validation houses weighted accordingly (`imitated`).
//!
//! `HOUSES` houses (seeds 0..HOUSES) are generated once and shared by the
//! tests. Every comparison is a goodness-of-fit test whose tolerance follows
//! from the sample size: binomial z-scores with a Bonferroni bound, Pearson's
//! chi-square against its 0.999 quantile, Kolmogorov-Smirnov distances against
//! their 0.999 critical value. A generator that draws from the wrong
//! distribution (for example the previous one, which forced four essential
//! rooms per floor and truncated furniture lists) fails them.

use std::collections::BTreeMap;
use std::sync::OnceLock;

use rayon::prelude::*;
use sornav_platform_sim::procedural::furniture::shape;
use sornav_platform_sim::procedural::{
    HM3D_FLOOR_COUNTS, HouseSize, HouseStats, STAIRWELL_LANDING, house_record,
};
use sornav_platform_sim::{NavMesh, NavMeshConfig, ProceduralConfig, RoomType, Scene};

const HOUSES: u64 = 160;

/// What one generated house looks like, as the tests count it.
struct House {
    seed: u64,
    floors: usize,
    /// Rooms as HM3D counts them: the stairwell and its landing are one room.
    rooms: usize,
    /// Walkable area of the floor islands of the height field (m^2).
    walkable: f64,
    /// Room type of every counted room (stairs merged into hallway).
    types: Vec<RoomType>,
    /// Furnished rooms: type and objects by category.
    furnished: Vec<(RoomType, BTreeMap<String, usize>)>,
}

fn class(t: RoomType) -> RoomType {
    if t == RoomType::Stairs {
        RoomType::Hallway
    } else {
        t
    }
}

fn describe(seed: u64, scene: &Scene, walkable: f64) -> House {
    let counted: Vec<_> = scene
        .rooms()
        .iter()
        .filter(|r| r.name != STAIRWELL_LANDING)
        .collect();
    let mut furnished: Vec<(RoomType, BTreeMap<String, usize>)> = scene
        .rooms()
        .iter()
        .map(|r| (r.room_type, BTreeMap::new()))
        .collect();
    for o in scene.objects() {
        let r = o.room.expect("every object lies in a room");
        *furnished[r].1.entry(o.category.clone()).or_default() += 1;
    }
    let furnished = furnished
        .into_iter()
        .zip(scene.rooms())
        .filter(|(_, r)| r.room_type != RoomType::Stairs && r.name != STAIRWELL_LANDING)
        .map(|(f, _)| f)
        .collect();
    House {
        seed,
        floors: scene.levels().len(),
        rooms: counted.len(),
        walkable,
        types: counted.iter().map(|r| class(r.room_type)).collect(),
        furnished,
    }
}

fn houses(shuffled: bool) -> &'static [House] {
    static PLAIN: OnceLock<Vec<House>> = OnceLock::new();
    static SHUFFLED: OnceLock<Vec<House>> = OnceLock::new();
    let cell = if shuffled { &SHUFFLED } else { &PLAIN };
    cell.get_or_init(|| {
        let cfg = ProceduralConfig {
            shuffled_semantics: shuffled,
            ..ProceduralConfig::default()
        };
        (0..HOUSES)
            .into_par_iter()
            .map(|seed| {
                let scene = Scene::procedural(seed, &cfg).unwrap();
                // the walkable area is only compared for the plain houses
                let walkable = if shuffled {
                    0.0
                } else {
                    NavMesh::build(&scene, &NavMeshConfig::default())
                        .unwrap()
                        .floor_area()
                };
                describe(seed, &scene, walkable)
            })
            .collect()
    })
}

fn stats() -> &'static HouseStats {
    HouseStats::embedded().unwrap()
}

/// Two-sided binomial z-score of `k` successes in `n` trials against `p`.
fn z_binomial(k: usize, n: usize, p: f64) -> f64 {
    let n = n as f64;
    let p = p.clamp(1e-9, 1.0 - 1e-9);
    (k as f64 - n * p) / (n * p * (1.0 - p)).sqrt()
}

/// Two-proportion z-score of `k` successes in `n` generated rooms against a
/// proportion `p` measured on `m` HM3D regions (pooled variance): the HM3D
/// figure is itself a sample, which matters for rare room types.
fn z_two_proportions(k: usize, n: usize, p: f64, m: usize) -> f64 {
    let (nf, mf) = (n as f64, m as f64);
    let q = k as f64 / nf;
    let pooled = ((k as f64 + p * mf) / (nf + mf)).clamp(1e-9, 1.0 - 1e-9);
    (q - p) / (pooled * (1.0 - pooled) * (1.0 / nf + 1.0 / mf)).sqrt()
}

/// Upper 0.999 quantile of the chi-square distribution with `df` degrees of
/// freedom (Wilson-Hilferty approximation, within 1 % for df >= 2).
fn chi2_999(df: usize) -> f64 {
    let k = df as f64;
    let z = 3.090_232; // standard normal 0.999 quantile
    k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)
}

/// One-sample Kolmogorov-Smirnov distance between `sample` and the
/// empirical distribution `target`.
fn ks_distance(sample: &[f64], target: &[f64]) -> f64 {
    let mut s = sample.to_vec();
    let mut t = target.to_vec();
    s.sort_by(f64::total_cmp);
    t.sort_by(f64::total_cmp);
    let cdf = |v: &[f64], x: f64| v.partition_point(|&y| y <= x) as f64 / v.len() as f64;
    s.iter()
        .chain(t.iter())
        .map(|&x| {
            let below = |v: &[f64]| v.partition_point(|&y| y < x) as f64 / v.len() as f64;
            (cdf(&s, x) - cdf(&t, x))
                .abs()
                .max((below(&s) - below(&t)).abs())
        })
        .fold(0.0, f64::max)
}

/// The distribution of the houses the generator imitates: each validation
/// house weighted by its floor class's share of HM3D's 900 scenes
/// ([`HM3D_FLOOR_COUNTS`]) over the validation houses of that class (the
/// generator draws a floor class, then a house of that class).
fn imitated(st: &HouseStats, value: impl Fn(&HouseSize) -> f64) -> Vec<(f64, f64)> {
    let class = |h: &HouseSize| h.floors.clamp(1, 4) as usize - 1;
    let mut per_class = [0usize; 4];
    for h in &st.houses {
        per_class[class(h)] += 1;
    }
    st.houses
        .iter()
        .map(|h| {
            let c = class(h);
            (
                value(h),
                f64::from(HM3D_FLOOR_COUNTS[c]) / per_class[c] as f64,
            )
        })
        .collect()
}

/// One-sample Kolmogorov-Smirnov distance between `sample` and the weighted
/// empirical distribution `target` (value, weight).
fn ks_weighted(sample: &[f64], target: &[(f64, f64)]) -> f64 {
    let mut s = sample.to_vec();
    s.sort_by(f64::total_cmp);
    let total: f64 = target.iter().map(|t| t.1).sum();
    let t_cdf = |x: f64, strict: bool| {
        target
            .iter()
            .filter(|t| if strict { t.0 < x } else { t.0 <= x })
            .map(|t| t.1)
            .sum::<f64>()
            / total
    };
    let s_cdf = |x: f64, strict: bool| {
        (if strict {
            s.partition_point(|&y| y < x)
        } else {
            s.partition_point(|&y| y <= x)
        }) as f64
            / s.len() as f64
    };
    s.iter()
        .copied()
        .chain(target.iter().map(|t| t.0))
        .map(|x| {
            (s_cdf(x, false) - t_cdf(x, false))
                .abs()
                .max((s_cdf(x, true) - t_cdf(x, true)).abs())
        })
        .fold(0.0, f64::max)
}

/// KS critical distance at level 0.001 for a sample of `n` against a fixed
/// distribution (c(0.001) = 1.95, conservative for discrete targets).
fn ks_critical(n: usize) -> f64 {
    1.95 / (n as f64).sqrt()
}

#[test]
fn house_sizes_follow_hm3d_metadata() {
    let hs = houses(false);
    let st = stats();
    // floors: the share of one-floor houses is HM3D's (all 900 scenes; the
    // full 1/2/3/4+ distribution is checked by `multi_floor::floor_counts_follow_hm3d`)
    let total: u32 = HM3D_FLOOR_COUNTS.iter().sum();
    let one = f64::from(HM3D_FLOOR_COUNTS[0]) / f64::from(total);
    let k1 = hs.iter().filter(|h| h.floors == 1).count();
    let z = z_binomial(k1, hs.len(), one);
    eprintln!(
        "floors: {k1}/{} one-floor houses, HM3D {one:.3}, z = {z:.2}",
        hs.len()
    );
    assert!(z.abs() < 3.29, "one-floor share: z = {z:.2}");
    // every house has the floors (four or more: four) and rooms of the HM3D
    // house it imitates
    let mut raised = 0;
    let mut short = Vec::new();
    for h in hs {
        let rec = house_record(h.seed, st).unwrap();
        assert_eq!(h.floors, rec.floors.clamp(1, 4) as usize, "seed {}", h.seed);
        // a house of F > 1 floors needs the stairwell, two rooms downstairs
        // and one on every upper floor
        let least = if h.floors > 1 { h.floors + 2 } else { 1 };
        let want = (rec.rooms as usize).max(least);
        if want != rec.rooms as usize {
            raised += 1;
        }
        if h.rooms != want {
            short.push((h.seed, h.rooms, want));
        }
    }
    // a layout can lose a room when a rectangle is too narrow to cut
    eprintln!("rooms differing from the record (seed, built, wanted): {short:?}");
    assert!(
        short.len() * 5 <= hs.len(),
        "{} of {} houses miss rooms: {short:?}",
        short.len(),
        hs.len()
    );
    let missing: usize = short.iter().map(|s| s.2 - s.1).sum();
    let wanted: usize = hs.iter().map(|h| h.rooms).sum::<usize>() + missing;
    assert!(
        missing * 50 <= wanted,
        "{missing} of {wanted} rooms missing"
    );
    eprintln!("rooms: {raised} houses raised to the multi-floor minimum");
    // rooms per house: KS against HM3D's num_rooms of the imitated houses
    // (validation houses weighted by HM3D's floor-class shares)
    let rooms: Vec<f64> = hs.iter().map(|h| h.rooms as f64).collect();
    let target = imitated(st, |h| f64::from(h.rooms));
    let d = ks_weighted(&rooms, &target);
    eprintln!("rooms KS {d:.3} (critical {:.3})", ks_critical(hs.len()));
    assert!(d < ks_critical(hs.len()), "rooms per house: KS {d:.3}");
    // walkable area: KS against HM3D's navigable area, and per house within
    // a factor 1.5 of the imitated house's area
    let area: Vec<f64> = hs.iter().map(|h| h.walkable).collect();
    let target = imitated(st, |h| h.navigable_area);
    let d = ks_weighted(&area, &target);
    let ratios: Vec<f64> = hs
        .iter()
        .map(|h| h.walkable / house_record(h.seed, st).unwrap().navigable_area)
        .collect();
    let mut sorted = ratios.clone();
    sorted.sort_by(f64::total_cmp);
    eprintln!(
        "area KS {d:.3} (critical {:.3}); walkable / HM3D area: min {:.2} median {:.2} max {:.2}",
        ks_critical(hs.len()),
        sorted[0],
        sorted[sorted.len() / 2],
        sorted[sorted.len() - 1]
    );
    // sign test: the walkable area is as often above as below the imitated
    // house's navigable area (median ratio 1)
    let above = ratios.iter().filter(|&&r| r > 1.0).count();
    let z = z_binomial(above, ratios.len(), 0.5);
    eprintln!(
        "area above the record in {above} of {} houses (z {z:.2})",
        ratios.len()
    );
    assert!(
        z.abs() < 3.29,
        "walkable area biased: {above} of {} above",
        ratios.len()
    );
    assert!(d < ks_critical(hs.len()), "walkable area: KS {d:.3}");
}

#[test]
fn room_types_follow_hm3d() {
    let hs = houses(false);
    let st = stats();
    // HM3D frequencies, stairs merged into hallways (Hall/stairwell)
    let mut mean: BTreeMap<RoomType, f64> = BTreeMap::new();
    let mut presence: BTreeMap<RoomType, f64> = BTreeMap::new();
    for r in &st.room_types {
        *mean.entry(class(r.room_type)).or_default() += r.mean_per_scene;
        if r.room_type != RoomType::Stairs {
            presence.insert(r.room_type, r.scene_presence);
        }
    }
    let m: f64 = mean.values().sum();
    let mut observed: BTreeMap<RoomType, usize> = BTreeMap::new();
    for h in hs {
        for &t in &h.types {
            *observed.entry(t).or_default() += 1;
        }
    }
    let n: usize = observed.values().sum();
    assert!(
        observed.keys().all(|t| mean.contains_key(t)),
        "room types outside the statistics: {observed:?}"
    );
    // Pearson chi-square; classes expecting fewer than 5 rooms are pooled
    let (mut chi2, mut df, mut pool_e, mut pool_o) = (0.0, 0usize, 0.0, 0.0);
    for (&t, &mt) in &mean {
        let e = n as f64 * mt / m;
        let o = observed.get(&t).copied().unwrap_or(0) as f64;
        eprintln!("  {t:?}: observed {o} expected {e:.1}");
        if e < 5.0 {
            pool_e += e;
            pool_o += o;
        } else {
            chi2 += (o - e).powi(2) / e;
            df += 1;
        }
    }
    if pool_e > 0.0 {
        chi2 += (pool_o - pool_e).powi(2) / pool_e;
        df += 1;
    }
    let crit = chi2_999(df - 1);
    eprintln!(
        "room types: chi2 {chi2:.1} on {} df (critical {crit:.1}), {n} rooms",
        df - 1
    );
    assert!(
        chi2 < crit,
        "room-type frequencies: chi2 {chi2:.1} >= {crit:.1}"
    );
    // Fraction of houses holding each type, among houses with at least as
    // many rooms as an HM3D scene has on average (smaller houses anchor a
    // type with a probability lowered to its expected count)
    let big: Vec<&House> = hs.iter().filter(|h| h.rooms as f64 >= m.ceil()).collect();
    let bound = 3.29; // two-sided 0.001 per type, before Bonferroni
    for (&t, &p) in &presence {
        if t == RoomType::Hallway || p * big.len() as f64 <= 5.0 {
            continue; // houses with stairs always hold their stairwell
        }
        let k = big.iter().filter(|h| h.types.contains(&t)).count();
        let z = z_binomial(k, big.len(), p);
        eprintln!("  presence {t:?}: {k}/{} vs {p:.3}, z = {z:.2}", big.len());
        assert!(z.abs() < bound, "{t:?} presence: z = {z:.2}");
    }
}

/// Expected instances of a present category: `1 + G` capped at the shape's
/// `max_per_room`, G geometric with mean `mean_count - 1` (the generator's
/// documented count model).
fn expected_count(mean_count: f64, cap: u32) -> f64 {
    let q = ((mean_count - 1.0) / mean_count).clamp(0.0, 0.9);
    (0..cap).map(|j| q.powi(j as i32)).sum()
}

/// Presence per (room type, category) and instances per present category,
/// over the furnished rooms of every type with at least 20 rooms.
struct CellStats {
    label: String,
    /// Rooms holding the category, rooms of the type.
    k: usize,
    n: usize,
    /// HM3D presence and number of HM3D regions of the type.
    p: f64,
    regions: usize,
    /// Instances counted, instances expected from the count model.
    instances: usize,
    expected_instances: f64,
}

fn cells(hs: &[House]) -> Vec<CellStats> {
    let mut rooms_of: BTreeMap<RoomType, Vec<&BTreeMap<String, usize>>> = BTreeMap::new();
    for h in hs {
        for (t, objs) in &h.furnished {
            rooms_of.entry(*t).or_default().push(objs);
        }
    }
    let mut out = Vec::new();
    for rs in &stats().room_types {
        let Some(rooms) = rooms_of.get(&rs.room_type) else {
            continue;
        };
        if rooms.len() < 20 {
            continue;
        }
        for cs in &rs.objects {
            let Some(sh) = shape(&cs.category) else {
                continue;
            };
            let k = rooms
                .iter()
                .filter(|r| r.get(&cs.category).is_some_and(|&c| c > 0))
                .count();
            out.push(CellStats {
                label: format!("{:?}/{}", rs.room_type, cs.category),
                k,
                n: rooms.len(),
                p: cs.presence,
                regions: rs.regions,
                instances: rooms.iter().filter_map(|r| r.get(&cs.category)).sum(),
                expected_instances: rooms.len() as f64
                    * cs.presence
                    * expected_count(cs.mean_count, sh.max_per_room),
            });
        }
    }
    out
}

/// Objects per room type: for every (room type, category) cell the fraction
/// of rooms holding the category is compared with HM3D's by a two-proportion
/// z-test, Bonferroni-corrected over the cells (family-wise level 0.001).
/// Furniture that does not fit into a full room is dropped (95 % of the
/// expected category presences and 88 % of the expected instances are there
/// in these houses), so in addition at least 93 % of the expected presences
/// and 82 % of the expected instances (capped at each shape's
/// `max_per_room`) must be there.
#[test]
fn objects_follow_hm3d_per_room_type() {
    let cs = cells(houses(false));
    assert!(cs.len() > 100, "only {} cells", cs.len());
    // two-sided family-wise 0.001 over the cells: z bound for 0.0005 / cells
    let bound = normal_quantile(1.0 - 0.0005 / cs.len() as f64);
    let (mut sum_k, mut sum_e, mut inst, mut inst_e) = (0.0, 0.0, 0.0, 0.0);
    for c in &cs {
        let z = z_two_proportions(c.k, c.n, c.p, c.regions);
        eprintln!(
            "  {}: {}/{} = {:.3} vs {:.3} (z {z:.2}); instances {} vs {:.1}",
            c.label,
            c.k,
            c.n,
            c.k as f64 / c.n as f64,
            c.p,
            c.instances,
            c.expected_instances
        );
        assert!(
            z.abs() < bound,
            "{}: z = {z:.2} (bound {bound:.2})",
            c.label
        );
        sum_k += c.k as f64;
        sum_e += c.n as f64 * c.p;
        inst += c.instances as f64;
        inst_e += c.expected_instances;
    }
    eprintln!(
        "{} cells (|z| bound {bound:.2}): presences {sum_k} / {sum_e:.1} expected, instances {inst} / {inst_e:.1}",
        cs.len()
    );
    assert!(sum_k >= 0.93 * sum_e, "presences {sum_k} of {sum_e:.1}");
    assert!(inst >= 0.82 * inst_e, "instances {inst} of {inst_e:.1}");
}

/// Shuffled semantics deals each room's object list to a random room of the
/// same house: the objects stay (per category, the totals over all houses
/// agree within sampling noise of the placement), the room-object
/// association goes (a category's presence no longer depends on the room
/// type: chi-square test of independence on room type x presence, per
/// category; without shuffling the same test rejects independence).
#[test]
fn shuffled_semantics_breaks_association_keeps_objects() {
    let plain = houses(false);
    let shuffled = houses(true);
    let totals = |hs: &[House]| {
        let mut t: BTreeMap<String, usize> = BTreeMap::new();
        for h in hs {
            for (_, objs) in &h.furnished {
                for (c, n) in objs {
                    *t.entry(c.clone()).or_default() += n;
                }
            }
        }
        t
    };
    let (a, b) = (totals(plain), totals(shuffled));
    let (na, nb): (usize, usize) = (a.values().sum(), b.values().sum());
    eprintln!("objects: plain {na}, shuffled {nb}");
    // the same lists are drawn; only placement in another room can fail
    assert!((na as f64 - nb as f64).abs() <= 0.05 * na as f64);
    for (c, &x) in &a {
        let y = b.get(c).copied().unwrap_or(0);
        // Poisson-scale noise of placement, 4 sigma, plus 10 %
        let tol = 4.0 * (x.max(y) as f64).sqrt() + 0.1 * x as f64;
        eprintln!("  {c}: plain {x}, shuffled {y}");
        assert!((x as f64 - y as f64).abs() <= tol, "{c}: {x} vs {y}");
    }
    // association: Cramer's V of room type x presence, per category
    let association = |hs: &[House], category: &str| -> (f64, f64, usize) {
        let mut table: BTreeMap<RoomType, [f64; 2]> = BTreeMap::new();
        for h in hs {
            for (t, objs) in &h.furnished {
                let has = objs.get(category).is_some_and(|&n| n > 0);
                table.entry(*t).or_default()[usize::from(has)] += 1.0;
            }
        }
        table.retain(|_, r| r[0] + r[1] >= 20.0);
        let total: f64 = table.values().map(|r| r[0] + r[1]).sum();
        let col = [
            table.values().map(|r| r[0]).sum::<f64>(),
            table.values().map(|r| r[1]).sum::<f64>(),
        ];
        let mut chi2 = 0.0;
        for r in table.values() {
            for j in 0..2 {
                let e = (r[0] + r[1]) * col[j] / total;
                if e > 0.0 {
                    chi2 += (r[j] - e).powi(2) / e;
                }
            }
        }
        ((chi2 / total).sqrt(), chi2, table.len() - 1)
    };
    for category in [
        "toilet",
        "bed",
        "sofa",
        "stove",
        "refrigerator",
        "bathtub",
        "shower",
        "sink",
    ] {
        let (v_plain, c_plain, df) = association(plain, category);
        let (v_shuf, c_shuf, _) = association(shuffled, category);
        eprintln!(
            "  {category}: Cramer's V plain {v_plain:.3} (chi2 {c_plain:.0}), shuffled {v_shuf:.3} (chi2 {c_shuf:.1}), df {df}, chi2 critical {:.1}",
            chi2_999(df)
        );
        // without shuffling the room type predicts the category (independence
        // rejected at 0.001, strong association) ...
        assert!(
            c_plain > chi2_999(df) && v_plain > 0.3,
            "{category}: no association"
        );
        // ... with shuffling at most a weak residue remains: large pieces
        // still fit large rooms better, which correlates with room type
        assert!(
            v_shuf < 0.2 && v_shuf < 0.25 * v_plain,
            "{category}: association survives shuffling (V {v_shuf:.3})"
        );
    }
}

/// Standard normal quantile (Acklam's rational approximation, relative error
/// below 1.2e-9).
fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969_683_028_665_376e1,
        2.209_460_984_245_205e2,
        -2.759_285_104_469_687e2,
        1.383_577_518_672_69e2,
        -3.066_479_806_614_716e1,
        2.506_628_277_459_239,
    ];
    const B: [f64; 5] = [
        -5.447_609_879_822_406e1,
        1.615_858_368_580_409e2,
        -1.556_989_798_598_866e2,
        6.680_131_188_771_972e1,
        -1.328_068_155_288_572e1,
    ];
    const C: [f64; 6] = [
        -7.784_894_002_430_293e-3,
        -3.223_964_580_411_365e-1,
        -2.400_758_277_161_838,
        -2.549_732_539_343_734,
        4.374_664_141_464_968,
        2.938_163_982_698_783,
    ];
    const D: [f64; 4] = [
        7.784_695_709_041_462e-3,
        3.224_671_290_700_398e-1,
        2.445_134_137_142_996,
        3.754_408_661_907_416,
    ];
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    if p < 0.02425 {
        tail((-2.0 * p.ln()).sqrt())
    } else if p > 1.0 - 0.02425 {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    } else {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    }
}

#[test]
fn statistical_helpers_match_tables() {
    // chi-square 0.999 quantiles: 8 df 26.12, 20 df 45.31
    assert!((chi2_999(8) - 26.12).abs() < 0.3, "{}", chi2_999(8));
    assert!((chi2_999(20) - 45.31).abs() < 0.4, "{}", chi2_999(20));
    assert!((normal_quantile(0.999) - 3.0902).abs() < 1e-3);
    assert!((normal_quantile(0.975) - 1.96).abs() < 1e-3);
    assert!((normal_quantile(0.001) + 3.0902).abs() < 1e-3);
    // KS distance of a sample against itself is 0, against a shifted copy 1
    let v: Vec<f64> = (0..50).map(f64::from).collect();
    assert_eq!(ks_distance(&v, &v), 0.0);
    let w: Vec<f64> = v.iter().map(|x| x + 100.0).collect();
    assert_eq!(ks_distance(&v, &w), 1.0);
    // the weighted KS equals the plain one for unit weights
    let vw: Vec<(f64, f64)> = w.iter().map(|&x| (x, 1.0)).collect();
    assert_eq!(ks_weighted(&v, &vw), 1.0);
    let half: Vec<(f64, f64)> = v.iter().map(|&x| (x, 2.0)).collect();
    assert_eq!(ks_weighted(&v, &half), 0.0);
}
