// A modal question for actions that can hurt (torque off with the arm raised): the page's own <dialog>,
// so the operator answers in the page and a test clicks the same buttons.

const $ = (id) => document.getElementById(id);

/** Ask `text` under `title`; resolves true when the operator presses the `ok` button, false otherwise. */
export function askConfirm({ title, text, ok = "OK" }) {
  const dialog = $("confirm-dialog");
  $("confirm-title").textContent = title;
  $("confirm-text").textContent = text;
  $("confirm-ok").textContent = ok;
  return new Promise((resolve) => {
    dialog.addEventListener("close", () => resolve(dialog.returnValue === "ok"), { once: true });
    dialog.returnValue = "";
    dialog.showModal();
  });
}
