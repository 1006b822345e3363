//! The candidate refits of one selection round, made ahead on the machine's cores.
//!
//! Within a round every refit starts from the same fit and is judged against the same one, so
//! a refit depends on its candidate alone. The round asks for them in its order (the best
//! candidates in turn, then the rivals of the first that passes); when it asks for one not made
//! yet, the next ones it may ask for are made at the same time on the other cores. The round,
//! its trials and the report are the same as when each refit is made when asked for: a refit
//! made ahead is the same computation, and one never asked for costs only another core's time
//! (its error, if any, is never seen).

use super::*;

/// A refit of candidate `e` of `k` parameters: `(e, k)`.
pub(super) type Wanted = (usize, usize);

/// The refits of a round, made when first asked for together with the next ones.
pub(super) struct Attempts<'a> {
    attempt: &'a (dyn Fn(usize, usize) -> Result<Attempt, CalibError> + Sync),
    made: HashMap<usize, Result<Attempt, CalibError>>,
    threads: usize,
}

impl<'a> Attempts<'a> {
    /// Refits made by `attempt(e, k)`, on up to `available_parallelism` threads at a time.
    pub(super) fn new(
        attempt: &'a (dyn Fn(usize, usize) -> Result<Attempt, CalibError> + Sync),
    ) -> Self {
        Self {
            attempt,
            made: HashMap::new(),
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }

    /// The refit of `wanted[0]`; when it is not made yet, it is made together with the first of
    /// `wanted[1..]` not made yet, one per core.
    ///
    /// # Errors
    /// The refit's own error; [`CalibError::NonFinite`] when a worker thread lost its result
    /// or `wanted` is empty.
    pub(super) fn take(&mut self, wanted: &[Wanted]) -> Result<Attempt, CalibError> {
        let lost = || CalibError::NonFinite {
            what: "a candidate refit was lost".into(),
        };
        let &(e, _) = wanted.first().ok_or_else(lost)?;
        if !self.made.contains_key(&e) {
            let mut batch: Vec<Wanted> = Vec::with_capacity(self.threads);
            for &w in wanted {
                if batch.len() < self.threads
                    && !self.made.contains_key(&w.0)
                    && !batch.iter().any(|b| b.0 == w.0)
                {
                    batch.push(w);
                }
            }
            let attempt = self.attempt;
            let results = dh_core::parallel::map(batch.len(), |i| attempt(batch[i].0, batch[i].1))
                .ok_or_else(lost)?;
            for (w, result) in batch.iter().zip(results) {
                self.made.insert(w.0, result);
            }
        }
        self.made.remove(&e).ok_or_else(lost)?
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Mutex;

    use super::*;

    fn trial(e: usize) -> Trial {
        Trial {
            label: format!("candidate {e}"),
            rms: 0.0,
            val_rms: None,
            f: 0.0,
            f_p: 1.0,
            f_threshold: 0.01,
            bic: (0.0, 0.0),
            held_out: None,
            accepted: false,
            reason: String::new(),
        }
    }

    /// Each refit is made once, the one asked for is returned, and the error of a refit made
    /// ahead reaches the caller only when it asks for that refit.
    #[test]
    fn refits_are_made_once_and_returned_when_asked_for() {
        let calls = Mutex::new(Vec::new());
        let attempt = |e: usize, _k: usize| -> Result<Attempt, CalibError> {
            calls.lock().expect("no panic").push(e);
            if e == 3 {
                return Err(CalibError::NonFinite {
                    what: "refit 3".into(),
                });
            }
            Ok((trial(e), None))
        };
        let mut made = Attempts::new(&attempt);
        let wanted = [(1, 1), (3, 2), (2, 1)];
        assert_eq!(made.take(&wanted).expect("refit 1").0.label, "candidate 1");
        assert_eq!(
            made.take(&wanted[2..]).expect("refit 2").0.label,
            "candidate 2"
        );
        assert!(matches!(
            made.take(&wanted[1..2]),
            Err(CalibError::NonFinite { .. })
        ));
        assert!(made.take(&[]).is_err());
        let mut calls = calls.lock().expect("no panic").clone();
        calls.sort_unstable();
        // On one core each refit is made when asked for; on more, the next ones with it.
        assert_eq!(calls, vec![1, 2, 3]);
    }
}
