//! Shared by the viz tests (`mod common;`): decoding `.rrd` byte streams into rerun's
//! messages and chunks. Each test file uses a part of it.
#![allow(dead_code)]

use rerun::external::re_log_encoding::DecoderApp;
use rerun::external::re_log_types::{LogMsg, StoreKind};
use rerun::log::Chunk;

/// Every message of an `.rrd`, in order (the footer is not a message).
pub fn messages(bytes: &[u8]) -> Vec<LogMsg> {
    DecoderApp::decode_eager(bytes)
        .expect("an rrd stream")
        .map(|m| m.expect("a message"))
        .collect()
}

/// Two saves of the same data hold the same messages. rerun writes the footer's
/// per-store manifests in `HashMap` order, so two saves may differ in the order (and, as
/// seen twice, the encoded length: 64 bytes in 56–62 MB) of those entries; the messages,
/// which are everything a viewer shows, must be identical.
pub fn assert_reproducible(a: &[u8], b: &[u8]) {
    assert_eq!(messages(a), messages(b));
}

/// Every chunk of every store in an `.rrd` byte stream, in order.
pub fn chunks(bytes: &[u8]) -> Vec<(StoreKind, Chunk)> {
    messages(bytes)
        .into_iter()
        .filter_map(|msg| match msg {
            LogMsg::ArrowMsg(store, arrow) => Some((
                store.kind(),
                Chunk::from_arrow_msg(&arrow).expect("a chunk"),
            )),
            _ => None,
        })
        .collect()
}

/// Every chunk of the recording store of an `.rrd` byte stream, in order.
pub fn recording_chunks(bytes: &[u8]) -> Vec<Chunk> {
    chunks(bytes)
        .into_iter()
        .filter_map(|(kind, c)| (kind == StoreKind::Recording).then_some(c))
        .collect()
}

/// The line names of a series entity, from the static `SeriesLines` rows among `chunks`
/// (the entity's).
pub fn static_line_names<'a>(chunks: impl Iterator<Item = &'a Chunk>) -> Vec<String> {
    chunks
        .filter(|c| c.is_static())
        .flat_map(|c| {
            c.iter_slices::<String>("SeriesLines:names".into())
                .flat_map(|names| names.into_iter().map(|n| n.to_string()))
                .collect::<Vec<_>>()
        })
        .collect()
}
