//! A fixed-length delay line counted in whole samples (neural ticks).

/// Ring buffer: [`DelayLine::push`] stores a sample, [`DelayLine::get`] reads the one
/// pushed `lag` pushes ago (lag 0 = the newest). Before enough pushes, reads return the
/// fill value. Storage is allocated once, at construction.
#[derive(Debug, Clone)]
pub struct DelayLine<T: Copy> {
    buf: Vec<T>,
    /// Index of the newest sample.
    head: usize,
}

impl<T: Copy> DelayLine<T> {
    /// A line that can be read up to `max_lag` samples back, filled with `fill`.
    pub fn new(max_lag: usize, fill: T) -> DelayLine<T> {
        DelayLine {
            buf: vec![fill; max_lag + 1],
            head: 0,
        }
    }

    /// Longest readable lag \[samples\].
    pub fn max_lag(&self) -> usize {
        self.buf.len() - 1
    }

    /// Stores the newest sample.
    pub fn push(&mut self, x: T) {
        self.head = (self.head + 1) % self.buf.len();
        self.buf[self.head] = x;
    }

    /// The sample pushed `lag` pushes ago; `lag` is clamped to [`DelayLine::max_lag`].
    pub fn get(&self, lag: usize) -> T {
        let n = self.buf.len();
        let lag = lag.min(n - 1);
        self.buf[(self.head + n - lag) % n]
    }
}
