//! Golden digests of a short rehearsal's `.rrd` (rapier's `snapshot_portability.rs` style,
//! beside `tests/tests/golden_digest.rs` for the session files and `diagnose_golden.rs` for
//! `diagnose --json`): `rigtwin rehearse reach-perturb --subjects 1 --seed 1 --max-trials 4
//! --rerun save=…` logs the very values it logged when these digests were taken. A refactor
//! of the viewer's logging must not move one; a change meant to change what is drawn moves
//! them, and its commit says why and which entities moved.
//!
//! **What is digested.** The file's bytes are not: rerun writes the footer's per-store
//! manifests from a `HashMap`, so two saves of the same data can differ there. The file is
//! decoded with rerun's own decoder and its chunks are turned into a canonical byte stream,
//! one SHA-256 per entity path of the recording store and one for the whole blueprint store
//! (the layout). An entity's stream holds its rows in the order they were logged (row-id
//! order), and each row holds:
//! - its timelines, sorted by name, each with its kind (sequence, duration) and its value
//!   (`tick`, `time` in ns, `trial`; none for a static row);
//! - its components, sorted by name (`Scalars:scalars`, …), each with its archetype, its
//!   component type and its arrow type, then its values bit for bit (little-endian f64/f32
//!   and integers, strings and booleans, lists, fixed-size lists, structs and unions
//!   recursively, nulls marked).
//!
//! The blueprint's stream is the same with each row's entity path in front.
//!
//! **What is excluded, and why.** Saving twice (other folder, other `--jobs`) gives
//! identical messages, so nothing in them is random per save: the project derives every id
//! (`viz::ids`, `viz::blueprint`). What the digest leaves out is what is an address rather
//! than a drawn value, and so may move with no logged value moving:
//! - the chunk ids and row ids (counters here, clock TUIDs under a live SDK): only the order
//!   of the rows counts;
//! - how rows are grouped into chunks (rows are digested one by one): splitting or
//!   merging chunks keeps the digests, which `regrouping_rows_and_renumbering_ids_keeps_the_digests`
//!   checks with clock-based ids;
//! - the `SetStoreInfo` messages (store ids: the recording id hashes the protocol's JSON
//!   form, so a new protocol field renames it; the store source carries this package's
//!   version, `store_version` rerun's) and the blueprint activation command (it names the
//!   blueprint store); the test checks only that there are two stores and one activation;
//! - the `.rrd` framing and footer (encoding options, compression, manifests).
//!
//! **Regenerating.** Run `GOLDEN_PRINT=1 cargo test --release -p rigtwin --test viz_golden
//! -- --nocapture` and paste the printed lines into `WANT`. Do it only when a change is
//! meant to change what is logged: a rehearsal's numbers (then `golden_digest.rs` moves
//! too), the viewer's entities, colours, labels, timelines or layout, or a rerun upgrade
//! that renames an archetype or component or changes its arrow type; the commit names
//! the entities that moved and why. A digest that moves without such a change is a bug.
//! The digests were taken at the commit that added this test.
#![cfg(feature = "rerun")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;
use std::sync::OnceLock;

use rerun::external::arrow::array::{Array, AsArray as _};
use rerun::external::arrow::datatypes::{
    DataType, Float16Type, Float32Type, Float64Type, Int8Type, Int16Type, Int32Type, Int64Type,
    UInt8Type, UInt16Type, UInt32Type, UInt64Type,
};
use rerun::external::re_log_types::{LogMsg, StoreKind};
use rerun::log::{Chunk, ChunkId, RowId};
use sha2::{Digest as _, Sha256};

mod common;

/// The key of the blueprint store's digest (entity paths start with `/`).
const BLUEPRINT: &str = "blueprint";

/// Digest per recording entity, and of the blueprint, of the rehearsal below.
const WANT: &[(&str, &str)] = &[
    (
        "/arm/links",
        "f46e3c09ebec201b251938862ce4e0bba987348bba9dcf2610de49a9af83c2b0",
    ),
    (
        "/arm/shoulder",
        "c10fbe18bf1bebd32e50900c7f1652a833e96ac0c61f7fa12868ad680bb99840",
    ),
    (
        "/ellipses/damping/estimate/axes",
        "8da9a33bd43fa860fe85b13443f3c03d859b8619fa15bd5db006616e0a375719",
    ),
    (
        "/ellipses/damping/estimate/outline",
        "bb510b07a26f788126e22bf439c15d1a318a649b12123b6412e7f1e79b1613a7",
    ),
    (
        "/ellipses/damping/truth/axes",
        "5c0b20cc985c6c4a7e76fd42ad0af4d5a2d7c19c13d18f2dc42de6533918471d",
    ),
    (
        "/ellipses/damping/truth/outline",
        "7d1d916af344f1c3cc8de12f9af8ba35ecc51026666797384d78a2d3761d872b",
    ),
    (
        "/ellipses/damping/truth_at_onset/axes",
        "5eb5ef2954a6b10e5f1fdf05aa20b4f18aa94232264f8f9f5c5529bf59fe9a02",
    ),
    (
        "/ellipses/damping/truth_at_onset/outline",
        "d9e9150c5dcd6fc8ee138f39e273f4755d7d56d744e0f1f1304d3be48c3e8fbe",
    ),
    (
        "/ellipses/stiffness/estimate/axes",
        "04effc04c06eaf827d56ba17e68e385c25b096d8204742dd3ceaf6fc4d93be65",
    ),
    (
        "/ellipses/stiffness/estimate/outline",
        "098f8a8ad4feb0bd905af3a4f3afed4b9083ebeab3fbc7ecb7bd404753a55645",
    ),
    (
        "/ellipses/stiffness/truth/axes",
        "6385d15161ce1efa37cf978869e2935a434e6403b7a7d75594dfc11c351d82f4",
    ),
    (
        "/ellipses/stiffness/truth/outline",
        "f7dbe17daa921f92ed96c6289ded3137fdc664dcc6811eb5f7fb3de0833a9853",
    ),
    (
        "/ellipses/stiffness/truth_at_onset/axes",
        "c1a009a3e83091df0e282c1d82ebc7c26e4febdac05f8426be8bc67e4bba1b5b",
    ),
    (
        "/ellipses/stiffness/truth_at_onset/outline",
        "f6a65cc543447eda96d40dced6c40e782c0235f4c39c82d0590a9e659a20962b",
    ),
    (
        "/events",
        "cfcc904feb959ba9427912f514ec9c480e4b76859791d97a05819d7659e4cac1",
    ),
    (
        "/plots/arm/angles_deg",
        "f31eaa0a1b5f3f42d8349f48f15240b996a32f6927c09aa478398d8d6597a359",
    ),
    (
        "/plots/command",
        "d1a1d900a62d603fe3a1425c200334687c06571c7e9e02f719b6cf406bdc54a5",
    ),
    (
        "/plots/force/pert",
        "89ab899281d5fbe5b21fb40eb820414eb8a425f3eef8d741f09ed2e0a32700c7",
    ),
    (
        "/plots/force/sensor",
        "2919278674b3da7f8e8c20c3cebd9160c69ad244d9ad90a50def227f7be573ad",
    ),
    (
        "/plots/impedance/damping/estimate",
        "b2275fd65ea81aa505ebc4dc6e87a3ac40c4cf997e788a36a7962ccbf4657f7c",
    ),
    (
        "/plots/impedance/damping/truth",
        "bf1d4ded76844e61534f7a408b3f37c62d6b8a641a1bcfae4d4d8525aa775705",
    ),
    (
        "/plots/impedance/damping/truth_at_onset",
        "8493ea5597cd081f3b811bed4cc731c10561df2ac64d2abf6e9f08043baccce9",
    ),
    (
        "/plots/impedance/stiffness/estimate",
        "630c433e340f90bfe54399cf18b797640e2bd1c7efe1cb35a6963404624b618e",
    ),
    (
        "/plots/impedance/stiffness/truth",
        "2fad3dbd372546b3d23e003642844435375652c1dc05f16e0110e00f346b778b",
    ),
    (
        "/plots/impedance/stiffness/truth_at_onset",
        "9a9ebaf3900620609c171b21aae927a04984ffbdfddb4b66871bec543b53b58d",
    ),
    (
        "/plots/muscles/activations_n",
        "87573293fb2e8875e92a79f5c46ed22564b66bd88f78e1b60cd33a39173eb1ae",
    ),
    (
        "/plots/position",
        "3d17181d1a2c9efe2438de1068b799db46306e0f6fc94a2544f189e67fcd40d6",
    ),
    (
        "/plots/reference",
        "c254b70607d0f66afccd22ee26c40734398e8eaae04d939e660451aef5bed451",
    ),
    (
        "/plots/response/x_mm",
        "db42233e663ccc03519e45921a8a19f3ce087b93a95e8c5a8854ed37359f2e7b",
    ),
    (
        "/plots/response/y_mm",
        "f4f6b09595c4298fdf37376a3ebb67f49d6198f91a204d9805018b702075b9b0",
    ),
    (
        "/plots/velocity",
        "34b87cdd320285a97c2f7a73acf7dc4ba87b682c4570c6af0392ad4ddf47bf07",
    ),
    (
        "/rig/carriage",
        "5444100a1a4d912030480a73d239de8961073b74fe50a67a727fbec5b40ba209",
    ),
    (
        "/rig/rails/x",
        "f40c01e57ec441792ee7dbf5dec9379edb06b6f4fce5ae3c5cbbd6353cca2236",
    ),
    (
        "/rig/workspace",
        "071d1c4ca74a60659168d2a149ace3afca4c168c4009085e0f23c1edd9e81849",
    ),
    (
        "/trial/onset",
        "e024728e679d60a9cc8e64c749f9e86651f6e4f32a3e1a7ce76b04093f49a8c8",
    ),
    (
        "/trial/path",
        "c926236d53c0d9da0e4080410f4946a9b29ad60e1c03886f1c805563bb38b055",
    ),
    (
        "/trial/perturbation",
        "bfd628e690fc847e0491cbf565faffd96954f5d9a652d992aefda7a5c934064d",
    ),
    (
        "/trial/targets",
        "ff29d66a2ae0e1c74a7d580dc82ba7090af62668a38f1608885430c2e880c078",
    ),
    (
        "blueprint",
        "1c8e659d0930de6b496895e6149ff8a55ea91688ee912b528a1e765bfdec7ac2",
    ),
];

/// The `.rrd` of `rigtwin rehearse reach-perturb --subjects 1 --seed 1 --max-trials 4
/// --jobs 2`, made once for the tests of this file. Seed 1's first four trials include a
/// force pulse, so the onset truth, the response windows and the Börner estimate are drawn.
fn rrd() -> &'static [u8] {
    static RRD: OnceLock<Vec<u8>> = OnceLock::new();
    RRD.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let rrd = dir.path().join("golden.rrd");
        let out = Command::new(env!("CARGO_BIN_EXE_rigtwin"))
            .args([
                "rehearse",
                "reach-perturb",
                "--subjects",
                "1",
                "--seed",
                "1",
            ])
            .args(["--max-trials", "4", "--jobs", "2", "--out"])
            .arg(dir.path().join("out"))
            .arg("--rerun")
            .arg(format!("save={}", rrd.display()))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "rigtwin rehearse: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(rrd).unwrap()
    })
}

// The canonical stream. Every field is tagged or length-prefixed, so two different
// contents cannot give the same bytes.

fn put_bytes(out: &mut Vec<u8>, bytes: &[u8]) {
    out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
    out.extend_from_slice(bytes);
}

fn put_str(out: &mut Vec<u8>, s: &str) {
    put_bytes(out, s.as_bytes());
}

/// An arrow type without its field metadata and list item names (how rerun's
/// serialisation names them is not a logged value); struct and union field names stay.
fn type_tag(datatype: &DataType) -> String {
    match datatype {
        DataType::List(f) | DataType::LargeList(f) => format!("List<{}>", type_tag(f.data_type())),
        DataType::FixedSizeList(f, n) => {
            format!("FixedSizeList<{n}, {}>", type_tag(f.data_type()))
        }
        DataType::Struct(fields) => {
            let fields: Vec<String> = fields
                .iter()
                .map(|f| format!("{}: {}", f.name(), type_tag(f.data_type())))
                .collect();
            format!("Struct<{}>", fields.join(", "))
        }
        DataType::Union(fields, mode) => {
            let fields: Vec<String> = fields
                .iter()
                .map(|(id, f)| format!("{id} {}: {}", f.name(), type_tag(f.data_type())))
                .collect();
            format!("Union<{mode:?}; {}>", fields.join(", "))
        }
        leaf => format!("{leaf:?}"),
    }
}

/// The slots of `array` (whatever its offset into shared buffers).
fn put_values(out: &mut Vec<u8>, array: &dyn Array) {
    out.extend_from_slice(&(array.len() as u64).to_le_bytes());
    for i in 0..array.len() {
        put_slot(out, array, i);
    }
}

/// Slot `i` of `array`: 0 if null, else 1 and its value, bit for bit.
fn put_slot(out: &mut Vec<u8>, array: &dyn Array, i: usize) {
    if array.is_null(i) {
        out.push(0);
        return;
    }
    out.push(1);
    macro_rules! primitive {
        ($t:ty) => {
            out.extend_from_slice(&array.as_primitive::<$t>().value(i).to_le_bytes())
        };
    }
    match array.data_type() {
        DataType::Null => {}
        DataType::Boolean => out.push(u8::from(array.as_boolean().value(i))),
        DataType::Int8 => primitive!(Int8Type),
        DataType::Int16 => primitive!(Int16Type),
        DataType::Int32 => primitive!(Int32Type),
        DataType::Int64 => primitive!(Int64Type),
        DataType::UInt8 => primitive!(UInt8Type),
        DataType::UInt16 => primitive!(UInt16Type),
        DataType::UInt32 => primitive!(UInt32Type),
        DataType::UInt64 => primitive!(UInt64Type),
        DataType::Float16 => primitive!(Float16Type),
        DataType::Float32 => primitive!(Float32Type),
        DataType::Float64 => primitive!(Float64Type),
        DataType::Utf8 => put_str(out, array.as_string::<i32>().value(i)),
        DataType::LargeUtf8 => put_str(out, array.as_string::<i64>().value(i)),
        DataType::Binary => put_bytes(out, array.as_binary::<i32>().value(i)),
        DataType::LargeBinary => put_bytes(out, array.as_binary::<i64>().value(i)),
        DataType::FixedSizeBinary(_) => put_bytes(out, array.as_fixed_size_binary().value(i)),
        DataType::List(_) => put_values(out, &array.as_list::<i32>().value(i)),
        DataType::LargeList(_) => put_values(out, &array.as_list::<i64>().value(i)),
        DataType::FixedSizeList(..) => put_values(out, &array.as_fixed_size_list().value(i)),
        DataType::Struct(_) => {
            for column in array.as_struct().columns() {
                put_slot(out, column, i);
            }
        }
        DataType::Union(..) => {
            let union = array.as_union();
            out.extend_from_slice(&union.type_id(i).to_le_bytes());
            put_slot(out, &union.value(i), 0);
        }
        other => panic!("no canonical form for arrow type {other:?}: add it to put_slot"),
    }
}

/// Row `row` of `chunk`: its timelines, then its non-null components.
fn put_row(out: &mut Vec<u8>, chunk: &Chunk, row: usize) {
    out.push(b'R');
    let mut timelines: Vec<_> = chunk.timelines().iter().collect();
    timelines.sort_by(|a, b| a.0.as_str().cmp(b.0.as_str()));
    for (name, column) in timelines {
        out.push(b'T');
        put_str(out, name.as_str());
        put_str(out, &column.timeline().typ().to_string());
        out.extend_from_slice(&column.times_raw()[row].to_le_bytes());
    }
    let mut columns: Vec<_> = chunk.components().0.values().collect();
    columns.sort_by(|a, b| a.descriptor.display_name().cmp(b.descriptor.display_name()));
    for column in columns {
        // A null cell is no data for this component in this row (rerun pads columns so
        // when rows with different components share a chunk).
        if column.list_array.is_null(row) {
            continue;
        }
        let d = &column.descriptor;
        out.push(b'C');
        put_str(out, d.display_name());
        put_str(out, d.archetype.as_ref().map_or("", |a| a.as_str()));
        put_str(out, d.component_type.as_ref().map_or("", |t| t.as_str()));
        put_str(out, &type_tag(column.list_array.data_type()));
        put_values(out, &column.list_array.value(row));
    }
}

/// The digests of `chunks`: one per entity path of the recording store, one for the
/// blueprint store.
fn digests_of(chunks: &[(StoreKind, Chunk)]) -> BTreeMap<String, String> {
    // Every row, by (key, row id): the order in which each entity's rows were logged.
    let mut rows: Vec<(String, RowId, &Chunk, usize)> = Vec::new();
    for (kind, chunk) in chunks {
        let key = match kind {
            StoreKind::Recording => chunk.entity_path().to_string(),
            StoreKind::Blueprint => BLUEPRINT.to_owned(),
        };
        for (row, id) in chunk.row_ids().enumerate() {
            rows.push((key.clone(), id, chunk, row));
        }
    }
    rows.sort_by(|a, b| (&a.0, a.1).cmp(&(&b.0, b.1)));
    let mut hashers: BTreeMap<String, Sha256> = BTreeMap::new();
    let mut out = Vec::new();
    for (key, _, chunk, row) in rows {
        out.clear();
        if key == BLUEPRINT {
            put_str(&mut out, &chunk.entity_path().to_string());
        }
        put_row(&mut out, chunk, row);
        hashers.entry(key).or_default().update(&out);
    }
    hashers
        .into_iter()
        .map(|(key, hasher)| {
            let hex = hasher
                .finalize()
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            (key, hex)
        })
        .collect()
}

#[test]
fn a_short_rehearsal_logs_the_pinned_values() {
    let bytes = rrd();
    // What the digests leave out: two stores opened and one layout activated, nothing else
    // but chunks.
    let mut stores = Vec::new();
    let mut activations = 0;
    for msg in common::messages(bytes) {
        match msg {
            LogMsg::SetStoreInfo(info) => stores.push(info.info.store_id.kind()),
            LogMsg::BlueprintActivationCommand(_) => activations += 1,
            LogMsg::ArrowMsg(..) => {}
        }
    }
    assert_eq!(stores, [StoreKind::Recording, StoreKind::Blueprint]);
    assert_eq!(activations, 1);

    let got = digests_of(&common::chunks(bytes));
    if std::env::var_os("GOLDEN_PRINT").is_some() {
        for (k, v) in &got {
            println!("(\"{k}\", \"{v}\"),");
        }
    }
    let want: BTreeMap<String, String> = WANT
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    let keys: BTreeSet<&String> = got.keys().chain(want.keys()).collect();
    let moved: Vec<String> = keys
        .into_iter()
        .filter(|k| got.get(*k) != want.get(*k))
        .map(|k| format!("{k}: {:?}, pinned {:?}", got.get(k), want.get(k)))
        .collect();
    assert!(
        moved.is_empty(),
        "the logged values moved:\n{}",
        moved.join("\n")
    );
}

/// The digests are of the rows, not of their chunks or ids: every chunk split in two, with
/// fresh clock-based chunk ids and row ids (as rerun's SDK stamps them) in the same order,
/// gives the same digests.
#[test]
fn regrouping_rows_and_renumbering_ids_keeps_the_digests() {
    let chunks = common::chunks(rrd());
    let mut next_row = RowId::new();
    let mut regrouped = Vec::new();
    for (kind, chunk) in &chunks {
        let half = chunk.num_rows() / 2;
        for (start, len) in [(0, half), (half, chunk.num_rows() - half)] {
            if len == 0 {
                continue;
            }
            let part = chunk
                .row_sliced_shallow(start, len)
                .clone_as(ChunkId::new(), next_row);
            for _ in 0..len {
                next_row = next_row.next();
            }
            regrouped.push((*kind, part));
        }
    }
    assert!(regrouped.len() > chunks.len());
    assert_eq!(digests_of(&regrouped), digests_of(&chunks));
}
