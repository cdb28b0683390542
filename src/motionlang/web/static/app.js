// The page: forms -> /api/... -> the viewer. Every failure is one line in the panel's
// status (the server's {"error": ...}), never a trace.
"use strict";

const $ = (id) => document.getElementById(id);
const viewer = new SkeletonViewer($("view"));
const state = { take: null, rig: null, t0: null, maxUpload: Infinity };
// request -> first frame drawn, milliseconds, one entry a generated take (benchmarks read it)
window.mlTimings = [];

function status(id, text, isError) {
  const el = $(id);
  el.textContent = text;
  el.classList.toggle("error", Boolean(isError));
}

async function call(url, options) {
  let res;
  try {
    res = await fetch(url, options);
  } catch (e) {
    throw new Error("the server does not answer (is motionlang serve still running?)");
  }
  const type = res.headers.get("content-type") || "";
  if (!res.ok) {
    const body = type.includes("json") ? await res.json() : { error: await res.text() };
    throw new Error(body.error || `${res.status} ${res.statusText}`);
  }
  return res;
}

function show(view) {
  viewer.setMotion(view);
  $("play").disabled = false;
  $("play").textContent = "Pause";
  $("scrub").disabled = false;
  $("scrub").max = String(view.n_frames - 1);
  document.body.dataset.frames = String(view.n_frames);
}

viewer.onFrame = (t, frame) => {
  $("scrub").value = String(frame);
  $("clock").textContent = `${t.toFixed(2)} s`;
};
viewer.onFirstDraw = () => {
  if (state.t0 !== null) {
    window.mlTimings.push(performance.now() - state.t0);
    state.t0 = null;
  }
};
$("play").onclick = () => {
  viewer.toggle();
  $("play").textContent = viewer.playing ? "Pause" : "Play";
};
$("scrub").oninput = () => {
  viewer.playing = false;
  $("play").textContent = "Play";
  viewer.seek(Number($("scrub").value) / viewer.motion.fps);
};
document.addEventListener("keydown", (e) => {
  if (e.code === "Space" && !["TEXTAREA", "INPUT", "SELECT"].includes(e.target.tagName)) {
    e.preventDefault();
    $("play").click();
  }
});

async function generate() {
  const seconds = $("seconds").value.trim();
  const body = {
    text: $("text").value, model: $("model").value || null,
    seconds: seconds === "" ? null : Number(seconds), seed: Number($("seed").value || 0),
    method: $("method").disabled ? null : $("method").value || null, rig: state.rig,
  };
  status("gen-status", "generating...");
  $("generate").disabled = true;
  state.t0 = performance.now();
  try {
    const view = await (await call("/api/generate", {
      method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body),
    })).json();
    state.take = view.id;
    show(view);
    const on = view.rig ? ` on ${$("rig-status").dataset.name}` : "";
    status("gen-status", `${view.model}: ${view.n_frames} frames, ` +
      `${(view.n_frames / view.fps).toFixed(1)} s${on}` +
      (view.notes.length ? ` (${view.notes.join("; ")})` : ""));
    document.body.dataset.take = view.id;
    for (const b of document.querySelectorAll("#downloads button")) b.disabled = false;
  } catch (e) {
    state.t0 = null;
    status("gen-status", e.message, true);
  } finally {
    $("generate").disabled = false;
  }
}

async function download(fmt) {
  if (!state.take) return;
  status("dl-status", `writing .${fmt}...`);
  try {
    const rig = state.rig ? `?rig=${encodeURIComponent(state.rig)}` : "";
    const res = await call(`/api/export/${state.take}.${fmt}${rig}`);
    const name = (/filename="([^"]+)"/.exec(res.headers.get("content-disposition") || "") || [])[1]
      || `motion.${fmt}`;
    const url = URL.createObjectURL(await res.blob());
    const a = document.createElement("a");
    a.href = url;
    a.download = name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 60000);
    status("dl-status", `downloaded ${name}`);
  } catch (e) {
    status("dl-status", e.message, true);
  }
}

function filesForm(input) {
  const form = new FormData();
  let size = 0;
  for (const f of input.files) { form.append("files", f, f.name); size += f.size; }
  if (size > state.maxUpload) {
    throw new Error(`the files are ${(size / 1048576).toFixed(1)} MiB; the largest upload ` +
      `this server takes is ${(state.maxUpload / 1048576).toFixed(1)} MiB`);
  }
  return form;
}

async function useRig() {
  if (!$("rig-file").files.length) { status("rig-status", "choose a BVH file first", true); return; }
  status("rig-status", "reading the rig...");
  try {
    const rig = await (await call("/api/rig", { method: "POST", body: filesForm($("rig-file")) })).json();
    state.rig = rig.id;
    $("rig-status").dataset.name = rig.name;
    $("rig-clear").disabled = false;
    status("rig-status", `rig: ${rig.name} (${rig.joints} joints); generate again to see it`);
  } catch (e) {
    status("rig-status", e.message, true);
  }
}

async function describe() {
  if (!$("describe-file").files.length) { status("describe-status", "choose a motion file first", true); return; }
  status("describe-status", "describing...");
  $("sentences").replaceChildren();
  $("timeline").replaceChildren();
  try {
    const view = await (await call("/api/describe", { method: "POST", body: filesForm($("describe-file")) })).json();
    show(view);
    status("describe-status", `${view.name}: ${view.seconds.toFixed(1)} s` +
      (view.notes.length ? ` (${view.notes.join("; ")})` : ""));
    for (const s of view.sentences) {
      const li = document.createElement("li");
      li.textContent = s.text;
      li.title = s.log_p === null ? "grounded: what the body does (motionlang.analysis)" : `log P = ${s.log_p}`;
      $("sentences").appendChild(li);
    }
    for (const seg of view.timeline) {
      const li = document.createElement("li");
      li.textContent = `${seg.start.toFixed(1)}-${seg.end.toFixed(1)} s  ${seg.text}`;
      li.onclick = () => viewer.seek(seg.start);
      $("timeline").appendChild(li);
    }
  } catch (e) {
    status("describe-status", e.message, true);
  }
}

async function search() {
  status("search-status", "searching...");
  $("hits").replaceChildren();
  try {
    const args = new URLSearchParams({q: $("query").value, k: "10"});
    for (const [id, key] of [["where", "where"], ["min-duration", "min_duration"]]) {
      if ($(id).value.trim()) args.set(key, $(id).value.trim());
    }
    const hits = await (await call(`/api/search?${args}`)).json();
    status("search-status", hits.length ? "" : "no match");
    for (const h of hits) {
      const li = document.createElement("li");
      // a hit the analysis found says why; one of the learned model alone shows its score
      const why = h.why ? h.why : `score ${h.score.toFixed(3)}`;
      li.textContent = `${h.file}  ${h.start.toFixed(1)}-${h.end.toFixed(1)} s  (${why})`;
      li.onclick = async () => {
        try {
          const args = `file=${encodeURIComponent(h.file)}&start=${h.start}&end=${h.end}`;
          show(await (await call(`/api/take?${args}`)).json());
        } catch (e) {
          status("search-status", e.message, true);
        }
      };
      $("hits").appendChild(li);
    }
  } catch (e) {
    status("search-status", e.message, true);
  }
}

async function start() {
  const info = await (await call("/api/info")).json();
  for (const m of info.models) {
    const opt = document.createElement("option");
    opt.value = m.name;
    opt.textContent = m.name;
    opt.dataset.deterministic = m.deterministic ? "1" : "";
    $("model").appendChild(opt);
  }
  // a deterministic model draws nothing: its decoding and seed would change nothing;
  // the decoding menu lists only what the chosen model accepts
  const fixed = () => {
    const opt = $("model").selectedOptions[0];
    const off = Boolean(opt && opt.dataset.deterministic);
    const own = info.models.find((m) => opt && m.name === opt.value);
    const menu = $("method");
    while (menu.options.length > 1) menu.remove(1);   // keep "the model's own"
    for (const m of (own && own.methods) || info.methods) {
      const o = document.createElement("option");
      o.value = m;
      o.textContent = m;
      menu.appendChild(o);
    }
    menu.disabled = off;
    $("seed").disabled = off;
  };
  $("model").onchange = fixed;
  fixed();
  $("seconds").max = String(info.max_seconds);
  state.maxUpload = info.max_upload_bytes;
  for (const fmt of info.exports) {
    const b = document.createElement("button");
    b.id = `dl-${fmt}`;
    b.textContent = `.${fmt}`;
    b.disabled = true;
    b.onclick = () => download(fmt);
    $("downloads").appendChild(b);
  }
  $("panel-search").hidden = !info.search;
  $("server-note").textContent = `${info.models.length} model(s) loaded; uploads up to ` +
    `${(info.max_upload_bytes / 1048576).toFixed(0)} MiB`;
  document.body.dataset.ready = "1";
}

$("generate").onclick = generate;
$("text").addEventListener("keydown", (e) => {
  if (e.key === "Enter" && !e.shiftKey) { e.preventDefault(); generate(); }
});
$("rig-upload").onclick = useRig;
$("rig-clear").onclick = () => {
  state.rig = null;
  $("rig-clear").disabled = true;
  status("rig-status", "rig: the 21-joint body");
};
$("describe").onclick = describe;
$("search").onclick = search;
$("query").addEventListener("keydown", (e) => { if (e.key === "Enter") search(); });
start().catch((e) => status("gen-status", e.message, true));
