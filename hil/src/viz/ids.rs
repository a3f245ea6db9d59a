//! Chunk and row ids from a counter instead of the wall clock.
//!
//! rerun's ids are TUIDs (nanoseconds since the epoch, then an increment). Left to itself the
//! SDK stamps them from the clock, so two saves of the same session would differ in every chunk
//! header. Here each chunk gets the TUID (`BASE_NANOS + n`, 0) and its rows get the
//! increments 1, 2, … of the same nanosecond (rerun's `from_auto_row_ids` does that), so ids
//! are unique, ordered as sent, and the same on every run.

use rerun::external::re_tuid::Tuid;
use rerun::log::{ChunkId, RowId};

/// 2026-01-01T00:00:00Z: a fixed origin, so ids look like plausible TUIDs in the viewer.
const BASE_NANOS: u64 = 1_767_225_600_000_000_000;

/// Hands out chunk ids in sending order.
#[derive(Debug, Default)]
pub(crate) struct IdSource {
    next: u64,
}

impl IdSource {
    /// The id of the next chunk; its rows take the following increments.
    pub(crate) fn chunk(&mut self) -> ChunkId {
        let id = ChunkId::from_tuid(Tuid::from_nanos_and_inc(BASE_NANOS + self.next, 0));
        self.next += 1;
        id
    }

    /// A row id for a message that is not a chunk row (the store info).
    pub(crate) fn message(&mut self) -> RowId {
        let id = RowId::from_tuid(Tuid::from_nanos_and_inc(BASE_NANOS + self.next, 0));
        self.next += 1;
        id
    }
}
