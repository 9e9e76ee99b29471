"""The quick study's reports as a person sees them: rendered in headless Chromium (Debian
package ``chromium``; ``.ci/run`` installs it when it can) at 1400 px wide.

A copy of each report page gets a script that runs after the page has loaded (images
included) and writes what it found into the page; Chromium's ``--dump-dom`` returns that."""

import json
import re
import shutil
import subprocess

import pytest

CHROMIUM = shutil.which("chromium")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="headless Chromium not installed (Debian package 'chromium'; "
                             ".ci/run installs it where apt-get works)")

WIDTH = 1400
#: Collects, once the page and its images have loaded: broken images, images without a
#: caption, table-of-contents links whose target is missing, and the page's scroll width.
PROBE = """<script>
window.addEventListener("load", () => {
  const images = [...document.images];
  const broken = images.filter(i => !i.complete || i.naturalWidth === 0).map(i => i.src);
  const uncaptioned = images.filter(i => {
    const figure = i.closest("figure");
    const caption = figure && figure.querySelector("figcaption");
    return !caption || caption.textContent.trim().length < 20;
  }).map(i => i.src);
  const links = [...document.querySelectorAll("nav.toc a")].map(a => a.getAttribute("href"));
  const unresolved = links.filter(h => !h.startsWith("#")
                                       || !document.getElementById(h.slice(1)));
  const report = {images: images.length, broken, uncaptioned, links: links.length, unresolved,
                  scrollWidth: document.documentElement.scrollWidth,
                  innerWidth: window.innerWidth};
  const out = document.createElement("pre");
  out.id = "probe";
  out.textContent = JSON.stringify(report);
  document.body.appendChild(out);
});
</script>"""


def render(page, tmp_path) -> dict:
    """What :data:`PROBE` found on ``page`` rendered at :data:`WIDTH` px."""
    text = page.read_text(encoding="utf-8")
    base = f'<base href="{page.parent.as_uri()}/">'
    probed = tmp_path / f"probe-{page.parent.name}.html"
    probed.write_text(text.replace("<head>", "<head>" + base, 1)
                      .replace("</body>", PROBE + "</body>", 1), encoding="utf-8")
    profile = tmp_path / f"profile-{page.parent.name}"
    result = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         f"--user-data-dir={profile}", "--allow-file-access-from-files",
         f"--window-size={WIDTH},1000", "--virtual-time-budget=20000", "--dump-dom",
         probed.as_uri()],
        capture_output=True, text=True, timeout=120)
    found = re.search(r'<pre id="probe">(.*?)</pre>', result.stdout, flags=re.DOTALL)
    assert found, f"Chromium gave no probe result (exit {result.returncode}): " \
                  f"{result.stderr[-2000:]}"
    return json.loads(found[1].replace("&quot;", '"').replace("&amp;", "&"))


@pytest.mark.parametrize("page", ["report.html", "hover/report.html", "forward/report.html"])
def test_report_renders_in_chromium(quick_study, tmp_path, page):
    """No broken image, a caption under every figure, every table-of-contents link resolves,
    and no horizontal scrollbar at 1400 px."""
    found = render(quick_study.out / page, tmp_path)
    assert found["images"] >= 1 and found["broken"] == [], found["broken"]
    assert found["uncaptioned"] == []
    assert found["links"] >= 2 and found["unresolved"] == []
    assert found["innerWidth"] == WIDTH
    assert found["scrollWidth"] <= found["innerWidth"], found


def test_the_probe_sees_each_fault(tmp_path):
    """A page with every fault the report test looks for: the probe reports each."""
    page = tmp_path / "faulty" / "report.html"
    page.parent.mkdir()
    page.write_text(
        '<!DOCTYPE html><html><head><meta charset="utf-8"></head><body>'
        '<nav class="toc"><a href="#here">here</a><a href="#nowhere">nowhere</a></nav>'
        '<h2 id="here">here</h2><img src="missing.png" alt="missing">'
        '<div style="width:2000px">wide</div></body></html>', encoding="utf-8")
    found = render(page, tmp_path)
    assert len(found["broken"]) == 1 and len(found["uncaptioned"]) == 1
    assert found["unresolved"] == ["#nowhere"]
    assert found["scrollWidth"] > found["innerWidth"]
