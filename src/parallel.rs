//! The batch engine: one way to run a kernel over `n` items on all cores.
//!
//! A batch of `n` items is cut into chunks of [`CHUNK`] items (boundaries at
//! multiples of `CHUNK`), which the threads of a rayon pool of
//! [`num_threads`] threads take in turn. Kernels are pure functions of the
//! item index (and, for kernels that draw randomness, of a generator
//! advanced to that index), so the result is bit-identical whatever the
//! number of threads.
//!
//! The pool is private to mcsample (sized by [`set_num_threads`], else
//! `MCSAMPLE_NUM_THREADS`, else the number of cores), and it is rebuilt in a
//! child process after `fork`, whose copy of the pool has no threads.

use crate::error::{Error, Result};
use rayon::ThreadPool;
use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

/// Items per work unit. Batches up to twice this size run on the calling
/// thread, where starting the pool would cost more than it saves.
pub const CHUNK: usize = 1 << 14;

/// The largest thread count accepted.
pub const MAX_THREADS: usize = 1024;

/// Name of the environment variable that bounds the thread count.
pub const THREADS_VAR: &str = "MCSAMPLE_NUM_THREADS";

/// Thread count set by [`set_num_threads`]; 0 when not set.
static REQUESTED: AtomicUsize = AtomicUsize::new(0);

struct Pool {
    pid: u32,
    threads: usize,
    pool: Arc<ThreadPool>,
}

static POOL: Mutex<Option<Pool>> = Mutex::new(None);

/// Output buffers a kernel writes, split between chunks at an item index:
/// a mutable slice (one element per item) or a tuple of them.
pub trait Outputs: Send + Sized {
    /// Splits into items `[0, mid)` and `[mid, ..)`.
    fn split_at_item(self, mid: usize) -> (Self, Self);
}

impl Outputs for () {
    fn split_at_item(self, _: usize) -> (Self, Self) {
        ((), ())
    }
}

impl<T: Send> Outputs for &mut [T] {
    fn split_at_item(self, mid: usize) -> (Self, Self) {
        self.split_at_mut(mid)
    }
}

macro_rules! outputs_tuple {
    ($($name:ident $idx:tt),+) => {
        impl<$($name: Outputs),+> Outputs for ($($name,)+) {
            fn split_at_item(self, mid: usize) -> (Self, Self) {
                $(let $name = self.$idx.split_at_item(mid);)+
                (($($name.0,)+), ($($name.1,)+))
            }
        }
    };
}
#[allow(non_snake_case)]
mod tuples {
    use super::Outputs;
    outputs_tuple!(A 0, B 1);
    outputs_tuple!(A 0, B 1, C 2);
    outputs_tuple!(A 0, B 1, C 2, D 3);
}

/// Sets the number of threads batch calls use (1 to [`MAX_THREADS`]).
///
/// # Errors
/// [`Error::Integer`] if `n` is 0 or above [`MAX_THREADS`].
pub fn set_num_threads(n: usize) -> Result<()> {
    check_thread_count("n", n)?;
    REQUESTED.store(n, Ordering::Relaxed);
    Ok(())
}

/// The number of threads batch calls use: the value given to
/// [`set_num_threads`], else `MCSAMPLE_NUM_THREADS`, else the number of cores.
///
/// # Errors
/// [`Error::Integer`] if `MCSAMPLE_NUM_THREADS` is set but is not a whole
/// number from 1 to [`MAX_THREADS`].
pub fn num_threads() -> Result<usize> {
    match REQUESTED.load(Ordering::Relaxed) {
        0 => default_threads(),
        n => Ok(n),
    }
}

fn check_thread_count(arg: &'static str, n: usize) -> Result<usize> {
    if (1..=MAX_THREADS).contains(&n) {
        Ok(n)
    } else {
        Err(Error::Integer {
            arg,
            value: n.to_string(),
            requirement: format!("the thread count must be from 1 to {MAX_THREADS}"),
        })
    }
}

fn default_threads() -> Result<usize> {
    static FROM_ENV: OnceLock<std::result::Result<usize, String>> = OnceLock::new();
    let parsed = FROM_ENV.get_or_init(|| match std::env::var(THREADS_VAR) {
        Err(_) => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
        Ok(text) => text
            .trim()
            .parse::<usize>()
            .ok()
            .filter(|n| (1..=MAX_THREADS).contains(n))
            .ok_or(text),
    });
    parsed.clone().map_err(|text| Error::Integer {
        arg: THREADS_VAR,
        value: format!("{text:?}"),
        requirement: format!("must be a whole number from 1 to {MAX_THREADS}"),
    })
}

/// The CPUs to pin the pool's threads to, one each, when the pool has one
/// thread for each CPU that the thread building it may run on (more than
/// one), on Linux. Left to the OS, the two threads of a 2-core machine,
/// woken for a batch of a millisecond, were often placed on the same CPU
/// and stayed there for many batches, each of which then took twice as
/// long. With fewer threads than CPUs they are not pinned: the OS may have
/// better places for them (CPUs shared with other work, a CPU quota below
/// the CPU count). Pinned, a thread no longer moves to balance the load of
/// several processes that each pin theirs (the work is still shared out
/// within the pool), and what it starts inherits its one CPU.
fn cpus_to_pin(threads: usize) -> Option<Vec<core_affinity::CoreId>> {
    if !cfg!(target_os = "linux") || threads < 2 {
        return None;
    }
    core_affinity::get_core_ids().filter(|cpus| cpus.len() == threads)
}

/// The pool for `threads` threads, (re)built when the count changed or the
/// process was forked since it was built.
fn pool(threads: usize) -> Result<Arc<ThreadPool>> {
    let mut guard = POOL.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let pid = std::process::id();
    if let Some(p) = guard.as_ref()
        && p.pid == pid
        && p.threads == threads
    {
        return Ok(Arc::clone(&p.pool));
    }
    if let Some(old) = guard.take()
        && old.pid != pid
    {
        // The pool's threads do not exist in a forked child: never touch it.
        std::mem::forget(old);
    }
    let mut builder = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("mcsample-{i}"));
    if let Some(cpus) = cpus_to_pin(threads) {
        builder = builder.start_handler(move |i| {
            if let Some(&cpu) = cpus.get(i) {
                // Advice only: a thread that cannot be pinned runs anywhere.
                core_affinity::set_for_current(cpu);
            }
        });
    }
    let pool = builder.build().map_err(|e| Error::ThreadPool {
        threads,
        message: e.to_string(),
    })?;
    let pool = Arc::new(pool);
    *guard = Some(Pool {
        pid,
        threads,
        pool: Arc::clone(&pool),
    });
    Ok(pool)
}

/// Runs `kernel(range, outputs)` over items `0..n`, in chunks of [`CHUNK`]
/// items on the pool (or at once on this thread for small batches or one
/// thread). Every thread of the pool is started at once (a broadcast) and
/// takes chunks in order until none are left: rayon's work splitting wakes
/// its sleeping threads one by one as work is split, and after the pool
/// had idled for a millisecond or more, a batch of a few milliseconds often
/// ran on one thread to its end (2^20 Sobol' points in 8 dimensions: 7.7 ms
/// on two threads after a 0.1 s pause, as on one; 3.6 ms without the
/// pause).
///
/// `outputs` holds one element per item; each call gets the elements of
/// its range. The kernel returns whether every input of its
/// range was valid; the result is true when all were.
///
/// # Errors
/// Only when the thread count cannot be determined (see [`num_threads`]).
pub fn for_each_chunk<O, K>(n: usize, outputs: O, kernel: K) -> Result<bool>
where
    O: Outputs,
    K: Fn(Range<usize>, O) -> bool + Sync,
{
    let threads = num_threads()?;
    if threads == 1 || n <= 2 * CHUNK {
        return Ok(kernel(0..n, outputs));
    }
    let pool = pool(threads)?;
    let chunks = Mutex::new(Chunks {
        next: 0,
        n,
        rest: Some(outputs),
    });
    let valid = AtomicBool::new(true);
    pool.broadcast(|_| {
        loop {
            let next = chunks.lock().unwrap_or_else(PoisonError::into_inner).take();
            let Some((range, outputs)) = next else { break };
            if !kernel(range, outputs) {
                valid.store(false, Ordering::Relaxed);
            }
        }
    });
    Ok(valid.into_inner())
}

/// The chunks of a batch not yet taken: items `next..n` and their outputs.
struct Chunks<O> {
    next: usize,
    n: usize,
    rest: Option<O>,
}

impl<O: Outputs> Chunks<O> {
    /// The next chunk's items and outputs, if any are left.
    fn take(&mut self) -> Option<(Range<usize>, O)> {
        let rest = self.rest.take()?;
        let start = self.next;
        let len = CHUNK.min(self.n - start);
        self.next = start + len;
        if self.next == self.n {
            return Some((start..self.n, rest));
        }
        let (chunk, rest) = rest.split_at_item(len);
        self.rest = Some(rest);
        Some((start..start + len, chunk))
    }
}

/// Runs `f` inside mcsample's pool, so that rayon's parallel iterators in
/// it use [`num_threads`] threads (for builds whose units of work are not
/// items of a batch, such as the rows of a table). Results must not depend
/// on the thread count; that is up to `f`.
///
/// # Errors
/// Only when the thread count cannot be determined (see [`num_threads`]).
pub fn install<R: Send>(f: impl FnOnce() -> R + Send) -> Result<R> {
    // Also for one thread: outside the pool, rayon's iterators would run on
    // its global pool, one thread per core.
    Ok(pool(num_threads()?)?.install(f))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_item_is_visited_once_with_its_own_index() {
        let n = 5 * CHUNK + 17;
        let mut out = vec![0usize; n];
        let mut twice = vec![0usize; n];
        let ok = for_each_chunk(n, (&mut out[..], &mut twice[..]), |range, (a, b)| {
            assert!(
                range.start % CHUNK == 0,
                "chunks start at multiples of CHUNK"
            );
            for (k, i) in range.enumerate() {
                a[k] = i;
                b[k] = 2 * i;
            }
            true
        })
        .unwrap();
        assert!(ok);
        assert!(out.iter().enumerate().all(|(i, &v)| v == i));
        assert!(twice.iter().enumerate().all(|(i, &v)| v == 2 * i));
    }

    #[test]
    fn one_invalid_chunk_makes_the_batch_invalid() {
        let n = 4 * CHUNK;
        let ok = for_each_chunk(n, (), |range, ()| !range.contains(&(3 * CHUNK + 5))).unwrap();
        assert!(!ok);
    }

    #[test]
    fn builds_use_the_thread_count_asked_for() {
        set_num_threads(1).unwrap();
        let one = install(rayon::current_num_threads).unwrap();
        REQUESTED.store(0, Ordering::Relaxed);
        assert_eq!(one, 1);
        let default = install(rayon::current_num_threads).unwrap();
        assert_eq!(default, num_threads().unwrap());
    }

    #[test]
    fn thread_count_is_checked() {
        assert!(set_num_threads(0).is_err());
        assert!(set_num_threads(MAX_THREADS + 1).is_err());
        assert!(num_threads().unwrap() >= 1);
    }
}
