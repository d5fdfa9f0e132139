//! One model served by three endpoints, over real loopback sockets: stub
//! OpenAI-compatible servers that answer after a delay of their own, and may start
//! failing. Benchmark episodes share one client; its requests must spread over the
//! endpoints by their speed, avoid one that fails (the episodes still finishing), and
//! each call of a transcript must name the endpoint that answered it. The API key is
//! sent to every server and written nowhere.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use coherent::session::backend::{BackendName, BackendRequest, EndpointSource};
use coherent::session::bench::{self, BenchConfig, EpisodesRequest};
use coherent::session::engine::{
    ApiKey, Backoff, Builtin, Cancel, DEFAULT_MAX_RESULTS_BYTES, OpenAiClient, OpenAiConfig,
    ResultLine, Subset, Task, read_results,
};
use coherent_agents::transcript;
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};

mod common;
// The stub model servers' side of HTTP, which coherent-agents' tests use too.
#[path = "../crates/coherent-agents/tests/common/http.rs"]
mod http;

use http::{Request, answer, completion, read_request};

const KEY: &str = "sk-endpoints-0123456789-SECRET";

/// What a stub server does, and what it saw.
struct Stub {
    url: String,
    /// Requests answered (with anything).
    served: AtomicUsize,
    /// From this many requests on, every request gets a 500.
    fail_from: usize,
    /// Requests that carried the key.
    with_key: AtomicUsize,
    delay: Duration,
}

/// Starts a stub that answers after `delay`, failing from its `fail_from`-th request.
async fn stub(delay: Duration, fail_from: usize) -> Arc<Stub> {
    let listener = TcpListener::bind("127.0.0.1:0")
        .await
        .expect("bind loopback");
    let stub = Arc::new(Stub {
        url: format!("http://{}/v1", listener.local_addr().expect("address")),
        served: AtomicUsize::new(0),
        fail_from,
        with_key: AtomicUsize::new(0),
        delay,
    });
    let serving = Arc::clone(&stub);
    tokio::spawn(async move {
        while let Ok((socket, _)) = listener.accept().await {
            tokio::spawn(connection(socket, Arc::clone(&serving)));
        }
    });
    stub
}

/// Serves requests on one kept-alive connection until the client closes it.
async fn connection(mut socket: TcpStream, stub: Arc<Stub>) {
    while let Some(Request {
        authorization,
        body,
    }) = read_request(&mut socket).await
    {
        if authorization.as_deref() == Some(&format!("Bearer {KEY}")) {
            stub.with_key.fetch_add(1, Ordering::SeqCst);
        }
        let n = stub.served.fetch_add(1, Ordering::SeqCst);
        tokio::time::sleep(stub.delay).await;
        let response = if n >= stub.fail_from {
            http(500, "{\"error\": \"the GPU fell over\"}")
        } else {
            http(200, &completion(&answer(&body), "stop"))
        };
        if socket.write_all(response.as_bytes()).await.is_err() {
            return;
        }
    }
}

fn http(status: u16, body: &str) -> String {
    format!(
        "HTTP/1.1 {status} X\r\ncontent-type: application/json\r\ncontent-length: {}\r\n\r\n{body}",
        body.len()
    )
}

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("coherent-endpoints-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// The first four tasks of the paper's subset in env0.
fn tasks() -> Vec<Arc<Task>> {
    let mut tasks = bench::choose(&common::env0(), &Subset::Paper40)
        .expect("env0 reads")
        .selection
        .tasks;
    tasks.truncate(4);
    tasks
}

/// PEFA on [`tasks`] for `seeds` seeds, six episodes and six requests at once, through
/// one client of the endpoints at `urls`; the results lines.
async fn bench_over(urls: &[String], seeds: u32, out: &Path) -> Vec<ResultLine> {
    let config = OpenAiConfig {
        base_urls: urls.to_vec(),
        api_key: Some(ApiKey::new(KEY)),
        concurrency: 6,
        connect_timeout: Duration::from_secs(2),
        read_timeout: Duration::from_secs(5),
        total_timeout: Duration::from_secs(10),
        backoff: Backoff {
            max_retries: 3,
            base: Duration::from_millis(50),
            cap: Duration::from_secs(1),
        },
        ..OpenAiConfig::new("unused", "stub-model")
    };
    let episodes = EpisodesRequest {
        backend: BackendRequest {
            name: BackendName::OpenAi,
            endpoint: EndpointSource::Client(Arc::new(
                OpenAiClient::new(config).expect("a client"),
            )),
            ..BackendRequest::default()
        },
        ..EpisodesRequest::new(vec![Builtin::Pefa.into()])
    };
    let config = BenchConfig {
        episodes: episodes.prepare().expect("valid settings"),
        seeds,
        concurrency: 6,
        out: out.join("results.jsonl"),
        max_results_bytes: DEFAULT_MAX_RESULTS_BYTES,
    };
    let outcome = bench::run(&tasks(), &config, &Cancel::default(), &mut |_| {})
        .await
        .expect("the benchmark runs");
    assert_eq!(outcome.written, outcome.total);
    assert_no_key(out);
    read_results(&config.out).expect("results").lines
}

/// No file under `dir` holds the key.
fn assert_no_key(dir: &Path) {
    for entry in std::fs::read_dir(dir).expect("a folder") {
        let path = entry.expect("an entry").path();
        if path.is_dir() {
            assert_no_key(&path);
        } else {
            let text = std::fs::read_to_string(&path).expect("readable");
            assert!(!text.contains(KEY), "{} holds the API key", path.display());
        }
    }
}

/// Calls per endpoint over every transcript of `lines`, and how many episodes had
/// calls answered by more than one endpoint.
fn calls_by_endpoint(lines: &[ResultLine]) -> (HashMap<String, usize>, usize) {
    let mut counts = HashMap::new();
    let mut mixed = 0;
    for line in lines {
        let t = transcript::read(Path::new(&line.transcript)).expect("a transcript");
        let mut here = HashMap::new();
        for call in t.rounds.iter().flat_map(|r| &r.calls) {
            let endpoint = call.endpoint.clone().expect("each call names its endpoint");
            assert!(call.answer.is_some(), "every call was answered in the end");
            *here.entry(endpoint).or_insert(0) += 1;
        }
        mixed += usize::from(here.len() > 1);
        for (endpoint, n) in here {
            *counts.entry(endpoint).or_insert(0) += n;
        }
    }
    (counts, mixed)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn requests_spread_over_three_endpoints_by_their_speed() {
    let fast = [
        stub(Duration::from_millis(20), usize::MAX).await,
        stub(Duration::from_millis(20), usize::MAX).await,
    ];
    let slow = stub(Duration::from_millis(100), usize::MAX).await;
    let urls: Vec<String> = [&fast[0], &fast[1], &slow]
        .iter()
        .map(|s| s.url.clone())
        .collect();
    let out = scratch("speed");
    let lines = bench_over(&urls, 2, &out).await;
    assert_eq!(lines.len(), 8);
    assert!(lines.iter().all(ResultLine::is_final), "{lines:?}");
    assert!(
        lines
            .iter()
            .all(|l| l.backend.base_url == Some(urls.join(",")))
    );
    let (calls, mixed) = calls_by_endpoint(&lines);
    let served: Vec<usize> = [&fast[0], &fast[1], &slow]
        .iter()
        .map(|s| s.served.load(Ordering::SeqCst))
        .collect();
    // The transcripts name the endpoint of every call; no call failed, so the servers'
    // counts are the transcripts' counts.
    for (stub, n) in [&fast[0], &fast[1], &slow].iter().zip(&served) {
        assert_eq!(calls.get(&stub.url), Some(n), "{calls:?}");
        assert_eq!(stub.with_key.load(Ordering::SeqCst), *n, "the key is sent");
    }
    // Five times slower, it holds each request five times as long, and so takes far
    // fewer: a ninth with six requests always in flight (1/100 ms against 1/20 ms twice),
    // a little more here, where episodes also think between calls (about 14%).
    let total: usize = served.iter().sum();
    assert!(
        served[2] > 0,
        "the slow endpoint takes its share: {served:?}"
    );
    assert!(
        served[2] * 2 < served[0].min(served[1]),
        "the slow endpoint takes far fewer: {served:?}"
    );
    assert!(
        served[0].max(served[1]) * 2 < total,
        "the fast ones share evenly: {served:?}"
    );
    assert!(mixed > 0, "one episode's calls go to several endpoints");
    let _ = std::fs::remove_dir_all(&out);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_endpoint_that_starts_failing_is_avoided_and_the_episodes_finish() {
    let good = [
        stub(Duration::from_millis(20), usize::MAX).await,
        stub(Duration::from_millis(20), usize::MAX).await,
    ];
    // It answers its first 10 requests, then fails every one.
    let failing = stub(Duration::from_millis(20), 10).await;
    let urls: Vec<String> = [&good[0], &good[1], &failing]
        .iter()
        .map(|s| s.url.clone())
        .collect();
    let out = scratch("failing");
    let lines = bench_over(&urls, 2, &out).await;
    assert_eq!(lines.len(), 8);
    assert!(
        lines.iter().all(ResultLine::is_final),
        "every episode finishes, none on a backend error: {lines:?}"
    );
    let (calls, _) = calls_by_endpoint(&lines);
    // Its 10 answers are in the transcripts; its failures were retried elsewhere.
    assert_eq!(calls.get(&failing.url), Some(&10), "{calls:?}");
    let failures = failing.served.load(Ordering::SeqCst) - 10;
    let others: Vec<usize> = good
        .iter()
        .map(|s| s.served.load(Ordering::SeqCst))
        .collect();
    assert!(failures >= 1, "it did fail");
    // Rested 50 ms, 100 ms, 200 ms... after each failure in a row, it is tried a
    // handful of times in a run of a few hundred requests.
    assert!(
        failures * 10 < others[0].min(others[1]),
        "the failing endpoint is avoided: {failures} failures, the others served {others:?}"
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_endpoint_nobody_listens_on_is_avoided() {
    let good = stub(Duration::from_millis(5), usize::MAX).await;
    // A port that was just free: connections are refused.
    let dead = {
        let listener = TcpListener::bind("127.0.0.1:0")
            .await
            .expect("bind loopback");
        format!("http://{}/v1", listener.local_addr().expect("address"))
    };
    let out = scratch("refused");
    let lines = bench_over(&[dead.clone(), good.url.clone()], 1, &out).await;
    assert_eq!(lines.len(), 4);
    assert!(lines.iter().all(ResultLine::is_final), "{lines:?}");
    let (calls, _) = calls_by_endpoint(&lines);
    assert_eq!(calls.get(&dead), None, "{calls:?}");
    assert_eq!(
        calls.get(&good.url),
        Some(&good.served.load(Ordering::SeqCst))
    );
    let _ = std::fs::remove_dir_all(&out);
}
