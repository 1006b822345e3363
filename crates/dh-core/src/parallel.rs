//! Independent pieces of work on the machine's cores, results in order.
//!
//! The one way the workspace runs a loop on several threads (scoped standard threads, no
//! thread pool): the results are the same whatever the number of threads, as long as each
//! piece depends on its index alone.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The threads this process may run work on: `available_parallelism` (1 when unknown), and 1 on
/// WebAssembly without atomics (a browser's main thread), where spawning a thread fails at
/// run time whatever the host machine has.
pub fn threads() -> usize {
    if cfg!(all(target_family = "wasm", not(target_feature = "atomics"))) {
        return 1;
    }
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `work(0..count)` on up to `available_parallelism` threads (one thread when `count` is 1 or
/// the machine has one core), each thread taking the next index as it finishes one; the results
/// in index order, or the first error in that order. A panic in `work` reaches the caller, as
/// from any scoped thread; `panicked()` stands for a result lost some other way (a poisoned
/// lock), never silently skipped.
///
/// # Errors
/// The first error of `work` in index order; `panicked()` for a lost result.
pub fn try_map<T: Send, E: Send>(
    count: usize,
    work: impl Fn(usize) -> Result<T, E> + Sync,
    panicked: impl Fn() -> E,
) -> Result<Vec<T>, E> {
    let threads = threads().min(count);
    if threads <= 1 {
        return (0..count).map(work).collect();
    }
    let next = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<Result<T, E>>>> = Mutex::new((0..count).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let k = next.fetch_add(1, Ordering::Relaxed);
                if k >= count {
                    break;
                }
                let out = work(k);
                if let Ok(mut s) = slots.lock() {
                    s[k] = Some(out);
                }
            });
        }
    });
    let Ok(slots) = slots.into_inner() else {
        return Err(panicked());
    };
    slots
        .into_iter()
        .map(|s| s.unwrap_or_else(|| Err(panicked())))
        .collect()
}

/// [`try_map`] for work that cannot fail: `None` when a result was lost.
pub fn map<T: Send>(count: usize, work: impl Fn(usize) -> T + Sync) -> Option<Vec<T>> {
    try_map(count, |k| Ok(work(k)), || ()).ok()
}

/// The items a [`pipeline`]'s producer sends, read by the consumer: in the order sent, by
/// any number of threads at once (each item reaches one of them).
pub struct Items<T> {
    rx: Mutex<std::sync::mpsc::Receiver<T>>,
}

impl<T> Items<T> {
    /// The next item, waiting for the producer; `None` once it has returned and everything it
    /// sent has been read.
    pub fn next(&self) -> Option<T> {
        self.rx.lock().ok()?.recv().ok()
    }
}

impl<T> Iterator for &Items<T> {
    type Item = T;
    fn next(&mut self) -> Option<T> {
        Items::next(self)
    }
}

/// `consume` on the calling thread while `produce` runs on a second thread from the start:
/// `produce` hands each item to `send`, which returns `false` once `consume` has returned
/// (then `produce` should return). At most `capacity` items wait between the two, so memory
/// stays bounded whatever the number of items.
///
/// For a producer that must run in order (a stateful oracle, a random sequence) beside work
/// that can overlap it: `consume` may first do work of its own while the producer runs ahead,
/// then read the items in order ([`Items::next`], or `for item in items`), on several threads
/// if it likes ([`on_each_core`]). A panic in either reaches the caller, as from any scoped
/// thread.
///
/// Where threads cannot run ([`threads`] is 1 on WebAssembly without atomics, whose standard
/// library compiles `std::thread::spawn` but fails it at run time), `produce` runs to its end
/// first, every item waiting in an unbounded channel, then `consume`: the same items in the
/// same order, without the memory bound.
pub fn pipeline<T: Send, R>(
    capacity: usize,
    produce: impl FnOnce(&mut dyn FnMut(T) -> bool) + Send,
    consume: impl FnOnce(&Items<T>) -> R,
) -> R {
    #[cfg(all(target_family = "wasm", not(target_feature = "atomics")))]
    {
        let _ = capacity;
        let (tx, rx) = std::sync::mpsc::channel();
        produce(&mut |item| tx.send(item).is_ok());
        drop(tx);
        consume(&Items { rx: Mutex::new(rx) })
    }
    #[cfg(not(all(target_family = "wasm", not(target_feature = "atomics"))))]
    pipeline_on_threads(capacity, produce, consume)
}

/// [`pipeline`] with the producer on its own scoped thread.
#[cfg(not(all(target_family = "wasm", not(target_feature = "atomics"))))]
fn pipeline_on_threads<T: Send, R>(
    capacity: usize,
    produce: impl FnOnce(&mut dyn FnMut(T) -> bool) + Send,
    consume: impl FnOnce(&Items<T>) -> R,
) -> R {
    let (tx, rx) = std::sync::mpsc::sync_channel(capacity.max(1));
    let items = Items { rx: Mutex::new(rx) };
    std::thread::scope(|scope| {
        scope.spawn(move || produce(&mut |item| tx.send(item).is_ok()));
        let out = consume(&items);
        // Dropping the receiver before the scope joins ends a producer blocked on a full channel.
        drop(items);
        out
    })
}

/// `work()` once on each of up to `available_parallelism` threads (the calling one among
/// them; only it on a one-core machine), every result in a list: for workers that share
/// their input through a queue ([`Items`]) and keep their own state. A panic in `work` reaches
/// the caller.
pub fn on_each_core<V: Send>(work: impl Fn() -> V + Sync) -> Vec<V> {
    let threads = threads();
    if threads <= 1 {
        return vec![work()];
    }
    std::thread::scope(|scope| {
        let others: Vec<_> = (1..threads).map(|_| scope.spawn(&work)).collect();
        let mut out = vec![work()];
        for h in others {
            match h.join() {
                Ok(v) => out.push(v),
                Err(panic) => std::panic::resume_unwind(panic),
            }
        }
        out
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_come_in_index_order_with_the_first_error() {
        let squares = map(1000, |k| k * k).unwrap();
        assert_eq!(squares, (0..1000).map(|k| k * k).collect::<Vec<_>>());
        let r: Result<Vec<usize>, usize> =
            try_map(100, |k| if k % 30 == 29 { Err(k) } else { Ok(k) }, || 0);
        assert_eq!(r, Err(29));
        assert_eq!(map(0, |k| k), Some(vec![]));
    }

    #[test]
    fn a_pipeline_reads_in_order_and_stops_its_producer() {
        let all: Vec<usize> = pipeline(
            2,
            |send| {
                for k in 0..1000 {
                    if !send(k) {
                        return;
                    }
                }
            },
            |items| items.collect(),
        );
        assert_eq!(all, (0..1000).collect::<Vec<_>>());
        // Read on every core: each item reaches one reader.
        let mut read: Vec<usize> = pipeline(
            3,
            |send| {
                for k in 0..1000 {
                    if !send(k) {
                        return;
                    }
                }
            },
            |items| {
                on_each_core(|| items.collect::<Vec<_>>())
                    .into_iter()
                    .flatten()
                    .collect()
            },
        );
        read.sort_unstable();
        assert_eq!(read, (0..1000).collect::<Vec<_>>());
        // A consumer that stops early: the producer sees `false` and the call returns.
        let sent = AtomicUsize::new(0);
        let first: Vec<usize> = pipeline(
            1,
            |send| {
                for k in 0.. {
                    if !send(k) {
                        return;
                    }
                    sent.fetch_add(1, Ordering::Relaxed);
                }
            },
            |items| items.take(3).collect(),
        );
        assert_eq!(first, vec![0, 1, 2]);
        assert!(sent.load(Ordering::Relaxed) >= 3);
    }
}
