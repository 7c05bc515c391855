"use strict";
// The 2AFC procedures of Sundstedt et al. 2007, section 6.2, in the browser.
//
// Timing: every display change is made inside a requestAnimationFrame callback, so it reaches
// the screen with that frame, and the frame's time stamp (the performance.now() time line) is
// recorded as the moment it appeared. A stimulus is held by counting frames until its nominal
// time has passed (within half a frame). The stamps go to the server with the answer, so
// the durations each participant actually saw can be audited.

const $ = (id) => document.getElementById(id);
const SCREENS = ["welcome", "instructions", "ready", "stage", "question", "done"];
const GAP_PX = 32;   // between the images of the reference condition (experiment.css)
const state = { plan: null, queue: [], total: 0, current: null, events: null,
                frameMs: 1000 / 60, pageHidden: false };

const INSTRUCTIONS = {
  "no-reference": "In each trial you will see two images, one after the other, for 4 seconds " +
    "each, with a grey screen of 2 seconds in between. Then you choose which of the two " +
    "images had the worse quality: the first or the second.",
  "reference": "In each trial you will see a reference image at the top and two images below " +
    "it, all for 8 seconds. Then you choose which of the two lower images is most similar " +
    "to the reference: the left or the right.",
};

function show(screen) {
  for (const id of SCREENS) $(id).hidden = id !== screen;
}

function frame() {
  return new Promise((resolve) => requestAnimationFrame(resolve));
}

// The first frame at which `ms` have passed since the frame stamped `start`.
async function frameAfter(start, ms) {
  let now;
  do { now = await frame(); } while (now - start < ms - state.frameMs / 2);
  return now;
}

// The display's frame interval: the median of a dozen frames (also lets the grey settle).
async function measureFrameInterval() {
  const stamps = [];
  for (let i = 0; i < 13; i++) stamps.push(await frame());
  const deltas = stamps.slice(1).map((t, i) => t - stamps[i]).sort((a, b) => a - b);
  return deltas[Math.floor(deltas.length / 2)];
}

async function api(method, path, body) {
  const options = { method, headers: {} };
  if (body !== undefined) {
    options.headers["Content-Type"] = "application/json";
    options.body = JSON.stringify(body);
  }
  try {
    const response = await fetch(path, options);
    let data = {};
    try { data = await response.json(); } catch (error) { data = {}; }
    return { status: response.status, ok: response.ok, data };
  } catch (error) {
    return { status: 0, ok: false, data: { error: "the experiment server cannot be reached" } };
  }
}

function displayInfo() {
  return {
    device_pixel_ratio: window.devicePixelRatio,
    screen_width: screen.width, screen_height: screen.height,
    viewport_width: window.innerWidth, viewport_height: window.innerHeight,
  };
}

// CSS size that shows an image pixel for pixel on the display (no scaling).
function nativeCss(pixels) {
  return pixels / window.devicePixelRatio;
}

function neededViewport(plan) {
  let width = 0, height = 0;
  for (const trial of plan.trials) {
    const w = nativeCss(trial.width), h = nativeCss(trial.height);
    const reference = plan.condition === "reference";
    width = Math.max(width, reference ? 2 * w + GAP_PX : w);
    height = Math.max(height, reference ? 2 * h + GAP_PX : h);
  }
  return [Math.ceil(width), Math.ceil(height)];
}

function startPlan(plan) {
  state.plan = plan;
  state.total = plan.trials.length;
  state.queue = plan.trials.filter((trial) => !trial.answered);
  if (state.queue.length === 0) {   // a participant coming back who has answered everything
    show("done");
    return;
  }
  $("instructions-text").textContent = INSTRUCTIONS[plan.condition];
  $("answer-a").textContent = plan.answers[0][0].toUpperCase() + plan.answers[0].slice(1);
  $("answer-b").textContent = plan.answers[1][0].toUpperCase() + plan.answers[1].slice(1);
  $("question-text").textContent = plan.question;
  const [width, height] = neededViewport(plan);
  const warning = $("size-warning");
  warning.hidden = window.innerWidth >= width && window.innerHeight >= height;
  warning.textContent = `The window is smaller than the images need (${width} x ${height}); ` +
    "please make it full screen before you begin.";
  show("instructions");
}

function nextTrial() {
  if (state.queue.length === 0) {
    show("done");
    return;
  }
  const done = state.total - state.queue.length;
  $("ready-text").textContent = `Trial ${done + 1} of ${state.total}. ` +
    "Look at the centre of the screen and press Start when you are ready.";
  show("ready");
}

async function load(img, url, trial) {
  img.classList.remove("on");
  img.style.width = `${nativeCss(trial.width)}px`;
  img.style.height = `${nativeCss(trial.height)}px`;
  img.src = url;
  await img.decode();
}

async function runTrial(trial) {
  const plan = state.plan;
  const timings = plan.timings_ms;
  const [a, b] = plan.answers;
  const imageA = $("image-a"), imageB = $("image-b"), reference = $("reference");
  const loads = [load(imageA, trial.images[a], trial), load(imageB, trial.images[b], trial)];
  if (plan.condition === "reference") loads.push(load(reference, trial.images.reference, trial));
  await Promise.all(loads);
  $("stage").className = plan.condition;
  state.pageHidden = document.hidden;
  show("stage");
  state.frameMs = await measureFrameInterval();
  const events = {};
  if (plan.condition === "no-reference") {
    events.first_on = await frame();
    imageA.classList.add("on");
    events.first_off = await frameAfter(events.first_on, timings.first);
    imageA.classList.remove("on");
    events.second_on = await frameAfter(events.first_off, timings.gap);
    imageB.classList.add("on");
    events.second_off = await frameAfter(events.second_on, timings.second);
    imageB.classList.remove("on");
  } else {
    events.on = await frame();
    for (const img of [reference, imageA, imageB]) img.classList.add("on");
    events.off = await frameAfter(events.on, timings.exposure);
    for (const img of [reference, imageA, imageB]) img.classList.remove("on");
  }
  events.frame_ms = state.frameMs;
  state.current = trial;
  state.events = events;
  $("answer-message").textContent = "";
  setAnswerButtons(true);
  show("question");
}

async function startTrial() {
  const button = $("start-trial-button");
  if (button.disabled) return;   // one trial at a time, however often it is clicked
  button.disabled = true;
  try {
    await runTrial(state.queue[0]);
  } catch (error) {
    // Loading failed before anything was shown: the trial can simply be started again.
    show("ready");
    $("ready-text").textContent = `The images could not be loaded (${error.message}). ` +
      "Press Start to try again.";
  } finally {
    button.disabled = false;
  }
}

function setAnswerButtons(enabled) {
  $("answer-a").disabled = !enabled;
  $("answer-b").disabled = !enabled;
}

async function answer(choice) {
  const trial = state.current;
  if (!trial) return;
  const events = { ...state.events, answer_at: performance.now() };
  setAnswerButtons(false);
  const result = await api("POST", "/api/answers", {
    participant_id: state.plan.participant_id, scene: trial.scene, choice, events,
    page_hidden: state.pageHidden,
  });
  // 409: this answer is already stored (a repeated click or a lost reply): go on.
  if (result.ok || result.status === 409) {
    state.current = null;
    state.queue.shift();
    nextTrial();
    return;
  }
  $("answer-message").textContent = `Not saved: ${result.data.error || result.status}. Please try again.`;
  setAnswerButtons(true);
}

async function register(event) {
  event.preventDefault();
  const form = new FormData($("register"));
  const body = {
    participant_id: String(form.get("participant_id") || "").trim(),
    age_range: form.get("age_range"),
    vision_corrected: form.get("vision_corrected") === "yes",
    display: displayInfo(),
  };
  $("register-message").textContent = "";
  $("resume-button").hidden = true;
  const result = await api("POST", "/api/participants", body);
  if (result.status === 409) {
    $("register-message").textContent = `${result.data.error}. If this is the same person ` +
      "coming back, resume; otherwise use another id.";
    $("resume-button").hidden = false;
    return;
  }
  if (!result.ok) {
    $("register-message").textContent = result.data.error || `error ${result.status}`;
    return;
  }
  startPlan(result.data);
}

async function resume() {
  const id = String(new FormData($("register")).get("participant_id") || "").trim();
  const result = await api("GET", `/api/participants/${encodeURIComponent(id)}`);
  if (!result.ok) {
    $("register-message").textContent = result.data.error || `error ${result.status}`;
    return;
  }
  startPlan(result.data);
}

async function begin() {
  try {
    if (document.fullscreenEnabled && !document.fullscreenElement) {
      await document.documentElement.requestFullscreen();
    }
  } catch (error) {
    // Full screen is a convenience; the window-size warning already said what is needed.
  }
  nextTrial();
}

async function init() {
  document.addEventListener("visibilitychange", () => {
    if (document.hidden) state.pageHidden = true;
  });
  $("register").addEventListener("submit", register);
  $("resume-button").addEventListener("click", resume);
  $("begin-button").addEventListener("click", begin);
  $("start-trial-button").addEventListener("click", startTrial);
  $("answer-a").addEventListener("click", () => answer(state.plan.answers[0]));
  $("answer-b").addEventListener("click", () => answer(state.plan.answers[1]));
  const config = await api("GET", "/api/config");
  const select = document.querySelector("select[name=age_range]");
  for (const range of config.data.age_ranges || []) {
    const option = document.createElement("option");
    option.value = option.textContent = range;
    select.append(option);
  }
}

init();
