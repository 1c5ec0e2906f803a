//! A tiny blocking WebDriver client (W3C WebDriver over HTTP/1.1 on `std::net`, JSON with
//! serde_json) driving Debian's `chromedriver` + headless `chromium`, for the report's browser
//! tests. No async runtime and no extra crates: the tests need a handful of commands
//! (navigate, execute script, pointer actions, find element, click, keys).

#![allow(dead_code)]

use super::skip;

use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Whether this is CI (`CI=true`), where a missing browser or driver fails the test.
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "0" && v != "false")
}

/// The first of `names` on PATH.
pub fn which(names: &[&str]) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    names.iter().find_map(|n| {
        std::env::split_paths(&path)
            .map(|d| d.join(n))
            .find(|p| p.is_file())
    })
}

/// chromium and chromedriver, or `None` (skip) where either is missing and CI is not set;
/// under CI a missing one panics, naming the package to install.
pub fn browser_and_driver() -> Option<(PathBuf, PathBuf)> {
    let browser = which(&["chromium", "chromium-browser", "google-chrome"]);
    let driver = which(&["chromedriver"]);
    match (browser, driver) {
        (Some(b), Some(d)) => Some((b, d)),
        (b, _) => {
            let missing = if b.is_none() {
                "chromium (apt-get install chromium chromium-driver)"
            } else {
                "chromedriver (apt-get install chromium-driver)"
            };
            if in_ci() {
                panic!("CI is set but {missing} is not installed");
            }
            skip::skipped(&format!("{missing} not installed (CI not set)"));
            None
        }
    }
}

/// A chromedriver process with one browser session; both end when it is dropped.
pub struct Session {
    driver: Child,
    port: u16,
    id: String,
    _profile: tempfile::TempDir,
}

impl Session {
    /// Starts `driver` on a free port and opens a headless `browser` session with a window
    /// of `width`×`height` CSS pixels.
    pub fn start(browser: &Path, driver: &Path, width: u32, height: u32) -> Session {
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .and_then(|l| l.local_addr())
            .map(|a| a.port())
            .expect("a free port");
        let child = Command::new(driver)
            .arg(format!("--port={port}"))
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("chromedriver starts");
        let profile = tempfile::tempdir().unwrap();
        let mut s = Session {
            driver: child,
            port,
            id: String::new(),
            _profile: profile,
        };
        let deadline = Instant::now() + Duration::from_secs(20);
        while s.request("GET", "/status", None).is_err() {
            assert!(Instant::now() < deadline, "chromedriver did not answer");
            std::thread::sleep(Duration::from_millis(100));
        }
        let caps = json!({"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:chromeOptions": {
                "binary": browser.to_string_lossy(),
                "args": [
                    "--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                    "--no-first-run", "--disable-background-networking", "--disable-component-update",
                    "--disable-sync", "--allow-file-access-from-files",
                    format!("--window-size={width},{height}"),
                    format!("--user-data-dir={}", s._profile.path().display()),
                ]
            }
        }}});
        let v = s
            .request("POST", "/session", Some(&caps))
            .unwrap_or_else(|e| panic!("new session: {e}"));
        s.id = v["sessionId"]
            .as_str()
            .unwrap_or_else(|| panic!("no session id in {v}"))
            .to_string();
        s
    }

    /// One HTTP request to the driver; the `value` of its JSON answer, or the error it names.
    fn request(&self, method: &str, path: &str, body: Option<&Value>) -> Result<Value, String> {
        let mut stream = TcpStream::connect(("127.0.0.1", self.port)).map_err(|e| e.to_string())?;
        stream
            .set_read_timeout(Some(Duration::from_secs(60)))
            .map_err(|e| e.to_string())?;
        let body = body.map(|b| b.to_string()).unwrap_or_default();
        let head = format!(
            "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nContent-Type: application/json; charset=utf-8\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
            self.port,
            body.len()
        );
        stream
            .write_all(head.as_bytes())
            .and_then(|_| stream.write_all(body.as_bytes()))
            .map_err(|e| e.to_string())?;
        let mut reader = BufReader::new(stream);
        let mut status = String::new();
        reader.read_line(&mut status).map_err(|e| e.to_string())?;
        let mut length = None;
        loop {
            let mut line = String::new();
            reader.read_line(&mut line).map_err(|e| e.to_string())?;
            let line = line.trim_end();
            if line.is_empty() {
                break;
            }
            if let Some((k, v)) = line.split_once(':') {
                if k.eq_ignore_ascii_case("content-length") {
                    length = v.trim().parse::<usize>().ok();
                }
            }
        }
        let mut text = Vec::new();
        match length {
            Some(n) => {
                text.resize(n, 0);
                reader.read_exact(&mut text).map_err(|e| e.to_string())?;
            }
            None => {
                reader.read_to_end(&mut text).map_err(|e| e.to_string())?;
            }
        }
        let v: Value = serde_json::from_slice(&text)
            .map_err(|e| format!("{status}: {e}: {}", String::from_utf8_lossy(&text)))?;
        if !status.contains(" 200 ") {
            return Err(format!("{}: {}", status.trim(), v["value"]));
        }
        Ok(v.get("value").cloned().unwrap_or(v))
    }

    fn cmd(&self, method: &str, path: &str, body: Option<Value>) -> Value {
        let full = format!("/session/{}{path}", self.id);
        self.request(method, &full, body.as_ref())
            .unwrap_or_else(|e| panic!("{method} {path}: {e}"))
    }

    /// Opens `page` (a file) and waits until `ready` (a JS expression) is true.
    pub fn open(&self, page: &Path, ready: &str) {
        let url = format!("file://{}", page.canonicalize().unwrap().display());
        self.cmd("POST", "/url", Some(json!({ "url": url })));
        let deadline = Instant::now() + Duration::from_secs(30);
        while self.eval(&format!("return !!({ready});")) != json!(true) {
            assert!(
                Instant::now() < deadline,
                "page never became ready: {ready}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Runs `script` (a function body; `return` gives the value) in the page.
    pub fn eval(&self, script: &str) -> Value {
        self.cmd(
            "POST",
            "/execute/sync",
            Some(json!({ "script": script, "args": [] })),
        )
    }

    /// The element matching the CSS `selector`.
    pub fn find(&self, selector: &str) -> String {
        let v = self.cmd(
            "POST",
            "/element",
            Some(json!({ "using": "css selector", "value": selector })),
        );
        v.as_object()
            .and_then(|o| o.values().next())
            .and_then(|v| v.as_str())
            .unwrap_or_else(|| panic!("no element {selector}: {v}"))
            .to_string()
    }

    pub fn click(&self, selector: &str) {
        let id = self.find(selector);
        self.cmd("POST", &format!("/element/{id}/click"), Some(json!({})));
    }

    /// The rendered text of the element matching `selector`.
    pub fn text(&self, selector: &str) -> String {
        let id = self.find(selector);
        self.cmd("GET", &format!("/element/{id}/text"), None)
            .as_str()
            .unwrap_or_default()
            .to_string()
    }

    /// Moves the mouse to (x, y) CSS pixels of the viewport, as a user's pointer would
    /// (the page receives real pointermove/mousemove events).
    pub fn hover(&self, x: f64, y: f64) {
        self.actions(json!([{
            "type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": [{"type": "pointerMove", "origin": "viewport", "x": x.round() as i64, "y": y.round() as i64, "duration": 0}]
        }]));
    }

    /// Drags the mouse from (x0, y0) to (x1, y1) with the left button held.
    pub fn drag(&self, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) {
        self.actions(json!([{
            "type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
            "actions": [
                {"type": "pointerMove", "origin": "viewport", "x": x0 as i64, "y": y0 as i64, "duration": 0},
                {"type": "pointerDown", "button": 0},
                {"type": "pointerMove", "origin": "viewport", "x": x1 as i64, "y": y1 as i64, "duration": 100},
                {"type": "pointerUp", "button": 0}
            ]
        }]));
    }

    /// Turns the mouse wheel by `dy` at (x, y) CSS pixels of the viewport.
    pub fn wheel(&self, x: f64, y: f64, dy: i64) {
        self.actions(json!([{
            "type": "wheel", "id": "wheel",
            "actions": [{"type": "scroll", "origin": "viewport", "x": x as i64, "y": y as i64, "deltaX": 0, "deltaY": dy, "duration": 0}]
        }]));
    }

    /// Presses and releases `key` on the page.
    pub fn key(&self, key: &str) {
        self.actions(json!([{
            "type": "key", "id": "keyboard",
            "actions": [{"type": "keyDown", "value": key}, {"type": "keyUp", "value": key}]
        }]));
    }

    fn actions(&self, actions: Value) {
        self.cmd("POST", "/actions", Some(json!({ "actions": actions })));
    }
}

impl Drop for Session {
    fn drop(&mut self) {
        if !self.id.is_empty() {
            let _ = self.request("DELETE", &format!("/session/{}", self.id), None);
        }
        let _ = self.driver.kill();
        let _ = self.driver.wait();
    }
}
